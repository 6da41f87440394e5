#!/usr/bin/env bash
# batch_test.sh — end-to-end test of clients/curl/batch.sh against the real service: starts
# `manipid serve --port 0` on a temporary database, simulates a folder of three CSV files
# (one with a different true m2, one with a space in its name), and checks that
#   1. batch.sh writes a summary with three succeeded rows and m2 near its true value;
#   2. running it again creates no dataset and no job (Idempotency-Key from the file hashes);
#   3. options the service refuses ({"free":["m9"]}) give a non-zero exit, the reason printed,
#      and a summary row per file saying why; a file that is not a trajectory does too;
#   4. a server started with --token: without the token the script stops at once, with
#      --token it succeeds;
#   5. usage errors exit 2 with a message;
#   6. --robot: a 7-joint URDF and a folder of its runs (one uniform, one with a real logger's
#      jittery time stamps and stale rows, made by clients/python/tests/robot_data.py with the
#      real binary) plus a validation run inside the folder: one robot, every run identified
#      against it with the friction asked for, the base parameters by name in the summary and
#      near the truth, the validation error small; a re-run creates no robot, dataset or job;
#      other friction makes new jobs only; a robot whose joints do not match, a broken URDF and
#      robot options without --robot fail with the reason;
#   7. a payload: the README's payload block word for word on a run with a tool on the tip link
#      (robot_data.py's tool.csv) and the arm identified in 6: the tool's mass, the torque with
#      and without it, the URDF with it mounted.
# Usage: clients/curl/tests/batch_test.sh path/to/manipid    (exit 0 when everything passes)
set -euo pipefail

[[ $# -eq 1 && -x "$1" ]] || { echo "usage: $0 path/to/manipid" >&2; exit 2; }
binary=$(realpath -- "$1")
batch="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/batch.sh"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
for tool in curl jq; do
  command -v "$tool" >/dev/null || { echo "batch_test: needs $tool" >&2; exit 2; }
done

work=$(mktemp -d "${TMPDIR:-/tmp}/manipid-batch-test.XXXXXX")
server_pid=""
stop_server() {
  if [[ -n "$server_pid" ]]; then
    kill -TERM "$server_pid" 2>/dev/null || true
    wait "$server_pid" 2>/dev/null || true
    server_pid=""
  fi
}
cleanup() {
  stop_server
  rm -rf -- "$work"
}
trap cleanup EXIT

failures=0
pass() { printf 'ok    %s\n' "$1"; }
fail() { printf 'FAIL  %s\n' "$1"; failures=$((failures + 1)); }
check() {  # check DESCRIPTION COMMAND...
  local what=$1
  shift
  if "$@"; then pass "$what"; else fail "$what"; fi
}

# start_server DB [serve options...]: sets $url from the first stdout line.
start_server() {
  local db=$1
  shift
  local fifo="$work/stdout.fifo"
  rm -f -- "$fifo"
  mkfifo -- "$fifo"
  "$binary" serve --port 0 --db "$db" --workers 2 "$@" >"$fifo" 2>>"$work/server.log" &
  server_pid=$!
  local line=""
  exec 3<"$fifo"
  IFS= read -r -t 30 line <&3 || true
  # Keep draining stdout so the server never blocks on a full pipe.
  cat <&3 >/dev/null &
  exec 3<&-
  if [[ "$line" != "listening on http://"* ]]; then
    echo "batch_test: server did not start: '$line'" >&2
    cat -- "$work/server.log" >&2
    exit 1
  fi
  url=${line##* }
}

jq_true() {  # jq_true FILTER JSON: the filter gives true
  jq -e "$1" <<<"$2" >/dev/null
}
help_shows_usage() {
  "$batch" --help | grep -q '^Usage: batch.sh --url URL --out SUMMARY.csv'
}

count() {  # count PATH [auth header]: the number of items over all pages
  local path=$1 total=0 token="" page
  shift
  while :; do
    page=$(curl -sS --fail-with-body "$@" "$url$path?page_size=1000${token:+&page_token=$token}")
    total=$((total + $(jq '.items | length' <<<"$page")))
    token=$(jq -r '.next_page_token // empty' <<<"$page")
    [[ -n "$token" ]] || break
  done
  echo "$total"
}

# ---- Data: three short noisy runs, the third with m2 = 24 instead of 25 -------------------
data="$work/runs"
mkdir -p -- "$data"
"$binary" simulate --duration 2 --seed 1 --noise-q 1e-5 --out "$data/run 1.csv" 2>/dev/null
"$binary" simulate --duration 2 --seed 2 --noise-q 1e-5 --out "$data/run-2.csv" 2>/dev/null
"$binary" simulate --duration 2 --seed 3 --noise-q 1e-5 --param m2=24 --out "$data/heavy,m2=24.csv" 2>/dev/null
echo "not a csv" >"$data/notes.txt"   # not *.csv: ignored

start_server "$work/jobs.db"
options='{"half_length":100,"band":0.2}'
summary="$work/summary.csv"

# ---- 1. First run -------------------------------------------------------------------------
status=0
"$batch" --url "$url" --out "$summary" --options "$options" "$data" >"$work/run1.out" 2>&1 || status=$?
check "first run exits 0" test "$status" -eq 0
[[ $status -eq 0 ]] || cat -- "$work/run1.out"
check "summary has a header and 3 rows" test "$(wc -l <"$summary")" -eq 4
check "header: file,job_id,state,<parameters>,final_cost,error" \
  test "$(head -n1 "$summary")" = '"file","job_id","state","m1","m2","m3","m4","l1","l2","l3","l4","final_cost","error"'
# The summary as JSON rows (a CSV reader in jq would be overkill: no field but `file` has a comma).
rows=$(python3 -c 'import csv,json,sys; print(json.dumps(list(csv.DictReader(open(sys.argv[1])))))' "$summary" 2>/dev/null || echo '[]')
check "all three succeeded" test "$(jq '[.[] | select(.state == "succeeded")] | length' <<<"$rows")" -eq 3
check "file names kept (space, comma)" \
  test "$(jq -r '[.[].file] | sort | join("|")' <<<"$rows")" = 'heavy,m2=24.csv|run 1.csv|run-2.csv'
check "m2 within 1 % of 25 for the two nominal runs" \
  jq_true '[.[] | select(.file != "heavy,m2=24.csv") | (.m2 | tonumber) - 25 | fabs < 0.25] | length == 2 and all' "$rows"
check "m2 within 1 % of 24 for the heavy run" \
  jq_true '[.[] | select(.file == "heavy,m2=24.csv") | (.m2 | tonumber) - 24 | fabs < 0.24] | length == 1 and all' "$rows"
check "final_cost is a number, error empty" \
  jq_true 'length == 3 and all(.[]; (.final_cost | tonumber) >= 0 and .error == "")' "$rows"
jobs_after_first=$(count /v1/jobs)
datasets_after_first=$(count /v1/datasets)
check "3 jobs and 3 datasets on the server" test "$jobs_after_first/$datasets_after_first" = 3/3

# ---- 2. Second run: nothing new -----------------------------------------------------------
cp -- "$summary" "$work/summary.first.csv"
status=0
# The same options written differently must give the same Idempotency-Key.
"$batch" --url "$url" --out "$summary" --options '{ "band": 0.2, "half_length": 100 }' "$data" \
  >"$work/run2.out" 2>&1 || status=$?
check "second run exits 0" test "$status" -eq 0
check "second run: no new jobs" test "$(count /v1/jobs)" -eq "$jobs_after_first"
check "second run: no new datasets" test "$(count /v1/datasets)" -eq "$datasets_after_first"
check "second run: same summary" cmp -s -- "$summary" "$work/summary.first.csv"
check "second run says the jobs existed" test "$(grep -c 'job job_[0-9a-f]* (existing)' "$work/run2.out")" -eq 3

# ---- 3. Failures --------------------------------------------------------------------------
status=0
"$batch" --url "$url" --out "$work/bad.csv" --options '{"free":["m9"]}' "$data" >"$work/bad.out" 2>&1 || status=$?
check "refused options: non-zero exit" test "$status" -ne 0
check "refused options: reason printed (code, field, detail)" \
  grep -q 'INVALID_FIELD (field free\[0\]): .*m9' "$work/bad.out"
check "refused options: 3 rows submit_failed with the reason" \
  test "$(grep -c '"submit_failed",.*INVALID_FIELD' "$work/bad.csv")" -eq 3
check "refused options: no new jobs" test "$(count /v1/jobs)" -eq "$jobs_after_first"

mixed="$work/mixed"
mkdir -p -- "$mixed"
cp -- "$data/run-2.csv" "$mixed/"
printf 't,q1\n0,0\n0.001,zero\n' >"$mixed/broken.csv"
status=0
"$batch" --url "$url" --out "$work/mixed.csv" --options "$options" "$mixed" >"$work/mixed.out" 2>&1 || status=$?
check "broken file: non-zero exit" test "$status" -eq 1
check "broken file: upload reason printed" grep -q 'broken.csv: upload failed: INVALID_FIELD' "$work/mixed.out"
check "broken file: the good file still succeeded" grep -q '^"run-2.csv","job_[0-9a-f]*","succeeded"' "$work/mixed.csv"
check "broken file: its row says upload_failed" grep -q '^"broken.csv","","upload_failed"' "$work/mixed.csv"
check "broken file: the good file's job was not duplicated" test "$(count /v1/jobs)" -eq "$jobs_after_first"

# ---- 4. Token -----------------------------------------------------------------------------
stop_server
start_server "$work/token.db" --token s3cret
status=0
"$batch" --url "$url" --out "$work/token.csv" "$mixed" >"$work/token-missing.out" 2>&1 || status=$?
check "no token: exit 1 before any upload" test "$status" -eq 1
check "no token: UNAUTHORIZED printed" grep -q 'UNAUTHORIZED' "$work/token-missing.out"
rm -f -- "$mixed/broken.csv"
status=0
"$batch" --url "$url" --out "$work/token.csv" --token s3cret --options "$options" "$mixed" >"$work/token.out" 2>&1 || status=$?
check "with --token: exit 0" test "$status" -eq 0
status=0
MANIPID_TOKEN=s3cret "$batch" --url "$url" --out "$work/token.csv" --options "$options" "$mixed" >"$work/token-env.out" 2>&1 || status=$?
check "with MANIPID_TOKEN: exit 0, no new job" test "$status/$(count /v1/jobs -H 'Authorization: Bearer s3cret')" = 0/1
stop_server

# ---- 5. Usage -----------------------------------------------------------------------------
status=0
"$batch" --out "$work/x.csv" "$data" >"$work/usage.out" 2>&1 || status=$?
check "missing --url: exit 2 with a message" test "$status" -eq 2
check "missing --url: says so" grep -q -- '--url is required' "$work/usage.out"
status=0
"$batch" --url http://127.0.0.1:9 --out "$work/x.csv" --options '[1,2]' "$data" >"$work/usage.out" 2>&1 || status=$?
check "options not an object: exit 2" test "$status" -eq 2
check "--help: exit 0 with the usage" help_shows_usage

# ---- 6. A URDF robot ---------------------------------------------------------------------
panda="$root/examples/robots/panda_like.urdf"
robot_runs="$work/robot-runs"
python3 "$root/clients/python/tests/robot_data.py" "$binary" "$panda" "$work/robot-data" >"$work/robot-data.json"
mkdir -p -- "$robot_runs"
cp -- "$work/robot-data/run.csv" "$work/robot-data/jitter.csv" "$work/robot-data/check.csv" "$robot_runs/"
start_server "$work/robot.db"
robot_summary="$work/robot-summary.csv"
status=0
"$batch" --url "$url" --out "$robot_summary" --robot "$panda" --friction viscous,coulomb,offset \
  --validate "$robot_runs/check.csv" "$robot_runs" >"$work/robot1.out" 2>&1 || status=$?
check "robot: first run exits 0" test "$status" -eq 0
[[ $status -eq 0 ]] || cat -- "$work/robot1.out"
robot_rows=$(python3 -c 'import csv,json,sys; print(json.dumps(list(csv.DictReader(open(sys.argv[1])))))' "$robot_summary" 2>/dev/null || echo '[]')
check "robot: the two runs identified, the validation run not" \
  test "$(jq -r '[.[] | "\(.file)=\(.state)"] | sort | join(" ")' <<<"$robot_rows")" = 'jitter.csv=succeeded run.csv=succeeded'
check "robot: header file,job_id,state,fit_relative_error,validation_relative_error,<base parameters>,error" \
  bash -c '[[ "$(head -n1 "$1")" == "\"file\",\"job_id\",\"state\",\"fit_relative_error\",\"validation_relative_error\",\"Izz1 + Iyy2\",\"mx2\",\"my2 - 0.316*m3"* && "$(head -n1 "$1")" == *",\"fv2\","*",\"fo7\",\"error\"" ]]' _ "$robot_summary"
check "robot: fv2 and fc2 by name near the truth (0.4, 0.7) for both runs" \
  jq_true '[.[] | ((.fv2 | tonumber) - 0.4 | fabs < 0.03) and ((.fc2 | tonumber) - 0.7 | fabs < 0.03)] | length == 2 and all' "$robot_rows"
check "robot: validation error under 1 % for both runs" \
  jq_true '[.[] | (.validation_relative_error | tonumber) < 0.01 and (.fit_relative_error | tonumber) < 0.01] | length == 2 and all' "$robot_rows"
check "robot: one robot, three datasets, two jobs on the server" \
  test "$(count /v1/robots)/$(count /v1/datasets)/$(count /v1/jobs)" = 1/3/2
robot_id=$(curl -sS "$url/v1/robots" | jq -r '.items[0].id')
jobs_ok=$(curl -sS "$url/v1/jobs" | jq --arg robot "$robot_id" \
            '[.items[] | .robot_id == $robot and .validation_dataset_id != null] | length == 2 and all')
check "robot: both jobs name the robot and the validation run" test "$jobs_ok" = true
job_id=$(jq -r '.[0].job_id' <<<"$robot_rows")
check "robot: the request carries friction viscous,coulomb,offset" \
  jq_true '.request.friction == ["viscous", "coulomb", "offset"]' "$(curl -sS "$url/v1/jobs/$job_id")"

cp -- "$robot_summary" "$work/robot-summary.first.csv"
status=0
"$batch" --url "$url" --out "$robot_summary" --robot "$panda" --friction viscous,coulomb,offset \
  --validate "$robot_runs/check.csv" "$robot_runs" >"$work/robot2.out" 2>&1 || status=$?
check "robot: second run exits 0" test "$status" -eq 0
check "robot: second run creates no robot, dataset or job" \
  test "$(count /v1/robots)/$(count /v1/datasets)/$(count /v1/jobs)" = 1/3/2
check "robot: second run says the robot and the jobs existed" \
  test "$(grep -c 'robot rb_[0-9a-f]* (existing)' "$work/robot2.out")/$(grep -c 'job job_[0-9a-f]* (existing)' "$work/robot2.out")" = 1/2
check "robot: second run, same summary" cmp -s -- "$robot_summary" "$work/robot-summary.first.csv"

status=0
"$batch" --url "$url" --out "$work/robot-none.csv" --robot "$panda" --friction none "$robot_runs" \
  >"$work/robot3.out" 2>&1 || status=$?
check "robot: no friction, no validation run: exit 0, three new jobs, nothing else new" \
  test "$status/$(count /v1/robots)/$(count /v1/datasets)/$(count /v1/jobs)" = 0/1/3/5
check "robot: without --validate the validation run is identified too, and no fv columns" \
  bash -c '[[ $(wc -l <"$1") -eq 4 && "$(head -n1 "$1")" != *"\"fv1\""* ]]' _ "$work/robot-none.csv"

status=0
"$batch" --url "$url" --out "$work/robot-ur5.csv" --robot "$root/examples/robots/ur5_like.urdf" "$robot_runs" \
  >"$work/robot-ur5.out" 2>&1 || status=$?
check "robot: 7-joint runs for a 6-joint robot: exit 1" test "$status" -eq 1
check "robot: each run refused, naming dataset_id" \
  test "$(grep -c '"submit_failed",.*INVALID_FIELD (field dataset_id): the dataset has 7 joints' "$work/robot-ur5.csv")" -eq 3
printf '<robot name="broken"><link name="a"/>' >"$work/broken.urdf"
status=0
"$batch" --url "$url" --out "$work/robot-broken.csv" --robot "$work/broken.urdf" "$robot_runs" \
  >"$work/robot-broken.out" 2>&1 || status=$?
check "robot: a broken URDF: exit 1, the reason printed, no summary" \
  bash -c '[[ $0 -eq 1 ]] && grep -q "broken.urdf: robot upload failed: INVALID_FIELD (field urdf)" "$1" && [[ ! -e "$2" ]]' \
  "$status" "$work/robot-broken.out" "$work/robot-broken.csv"

# ---- 7. A payload: the README's block word for word, on the arm identified above ----------
payload_dir="$work/payload"
mkdir -p -- "$payload_dir"
cp -- "$work/robot-data/tool.csv" "$payload_dir/"
sed -n '/^### A payload on the tip link/,/^Delete a robot/p' "$root/clients/curl/README.md" |
  sed -n '/^```sh$/,/^```$/p' | sed '1d;$d' >"$payload_dir/readme.sh"
status=0
(cd "$payload_dir" && M="$url" RB="$robot_id" JOB="$job_id" bash -euo pipefail readme.sh) >"$work/payload.out" 2>&1 || status=$?
check "payload: the README's block runs" test "$status" -eq 0
[[ $status -eq 0 ]] || cat -- "$work/payload.out"
tool_mass=$(jq '.tool_truth.mass' "$work/robot-data.json")
check "payload: detected, the mass within 3 % of the tool's" \
  jq_true ".detected and ((.mass - $tool_mass) | fabs) < 0.03 * $tool_mass" "$(sed -n 1p "$work/payload.out")"
check "payload: the fit with the payload is better than without it" \
  jq_true '.with_payload < .arm_only / 2' "$(sed -n 3p "$work/payload.out")"
check "payload: the URDF with the payload mounted" grep -q '<link name="manipid_payload"' "$payload_dir/arm-with-tool.urdf"
check "payload: one payload_identification job on the robot" \
  test "$(curl -sS "$url/v1/jobs?kind=payload_identification&robot_id=$robot_id" | jq '.items | length')" -eq 1
stop_server
status=0
"$batch" --url http://127.0.0.1:9 --out "$work/x.csv" --friction viscous "$robot_runs" >"$work/usage.out" 2>&1 || status=$?
check "--friction without --robot: exit 2 with a message" \
  bash -c '[[ $0 -eq 2 ]] && grep -q -- "--friction needs --robot" "$1"' "$status" "$work/usage.out"
status=0
"$batch" --url http://127.0.0.1:9 --out "$work/x.csv" --robot "$work/missing.urdf" "$robot_runs" >"$work/usage.out" 2>&1 || status=$?
check "--robot with a missing file: exit 2" test "$status" -eq 2

if [[ $failures -gt 0 ]]; then
  echo "batch_test: $failures check(s) failed; server log:" >&2
  tail -n 20 -- "$work/server.log" >&2
  exit 1
fi
echo "batch_test: all checks passed"
