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
#   5. usage errors exit 2 with a message.
# Usage: clients/curl/tests/batch_test.sh path/to/manipid    (exit 0 when everything passes)
set -euo pipefail

[[ $# -eq 1 && -x "$1" ]] || { echo "usage: $0 path/to/manipid" >&2; exit 2; }
binary=$(realpath -- "$1")
batch="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/batch.sh"
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

if [[ $failures -gt 0 ]]; then
  echo "batch_test: $failures check(s) failed; server log:" >&2
  tail -n 20 -- "$work/server.log" >&2
  exit 1
fi
echo "batch_test: all checks passed"
