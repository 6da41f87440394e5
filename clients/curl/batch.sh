#!/usr/bin/env bash
# batch.sh — submits every *.csv file of a folder to a manipid service for identification,
# waits for all the jobs and writes one summary CSV. Needs only bash, curl, jq and coreutils.
#
#   clients/curl/batch.sh --url http://127.0.0.1:8080 --out summary.csv \
#       [--options '{"half_length": 100, "band": 0.2}'] [--token TOKEN] [--timeout S] DIR
#   clients/curl/batch.sh --url ... --out summary.csv --robot arm.urdf \
#       [--friction viscous,coulomb,offset] [--validate check.csv] [--options '{"trim": [1, 1]}'] DIR
#
# With --robot, the URDF is uploaded once (POST /v1/robots, Idempotency-Key batch-rb-<sha256 of
# the file>), so is the --validate run, and every file is identified against the robot (a
# robot identification: robot_id, dataset_id, validation_dataset_id, friction, the options).
#
# Each file is uploaded (POST /v1/datasets) with Idempotency-Key batch-ds-<sha256 of the file>
# and identified (POST /v1/identifications, the options merged with {"dataset_id": ...}) with
# Idempotency-Key batch-id-<sha256 of the file>-<sha256 of that request>: running the script
# again — after an interruption, or to collect the results — finds the same datasets and jobs
# instead of creating new ones. The summary has the columns
#   file,job_id,state,<estimate of each parameter, by name>,final_cost,error
# (with --robot: file,job_id,state,fit_relative_error,validation_relative_error,<estimate of
# each base parameter, by name>,error) with state one of succeeded, failed, cancelled,
# queued/running (still going at --timeout), upload_failed or submit_failed. Exit status: 0 when every job succeeded, 1 when any upload,
# submission or job did not (the reasons are printed), 2 for a usage error.
set -euo pipefail

program=${0##*/}

usage() {
  cat <<EOF
Usage: $program --url URL --out SUMMARY.csv [--options JSON] [--token TOKEN] [--timeout SECONDS] DIR
       $program --url URL --out SUMMARY.csv --robot URDF [--friction TERMS] [--validate CSV] [...] DIR

Uploads every *.csv file in DIR to the manipid service at URL, submits an identification for
each (the JSON object OPTIONS plus {"dataset_id": ...}), waits for all and writes SUMMARY.csv:
file,job_id,state,<estimates by parameter name>,final_cost,error.
With --robot, the files are runs of that URDF robot (t,q1..qn[,qd..,qdd..],tau1..taun) and
each is identified against it; SUMMARY.csv then has file,job_id,state,fit_relative_error,
validation_relative_error,<estimate of each base parameter by name>,error.

Re-running with the same files and options creates no new robots, datasets or jobs
(Idempotency-Key from the SHA-256 of each file and of the request).

Options:
  --url URL           service address, e.g. http://127.0.0.1:8080
  --out FILE          summary CSV to write (replaced when the script ends)
  --options JSON      identification options, e.g. '{"half_length":100,"band":0.2}' (default {});
                      with --robot e.g. '{"armature":true,"trim":[1,1],"weights":"per-joint"}'
  --robot URDF        identify a URDF robot's base parameters (uploaded once)
  --friction TERMS    with --robot: viscous,coulomb,offset (any of them), none, or auto (the
                      service's default: chosen by held-out prediction)
                      (default: the service's, viscous,coulomb)
  --validate CSV      with --robot: a run every estimate predicts (its error in the summary);
                      skipped as a run to identify if it lies in DIR
  --token TOKEN       bearer token (default: \$MANIPID_TOKEN when set)
  --timeout SECONDS   stop waiting for the jobs after this long (default 0: no limit);
                      unfinished jobs are reported and a re-run picks them up again
  -h, --help          this text

Exit status: 0 all jobs succeeded; 1 an upload, submission or job failed; 2 usage error.
EOF
}

die_usage() {
  printf '%s: %s\n' "$program" "$1" >&2
  printf "Try '%s --help'.\n" "$program" >&2
  exit 2
}

log() { printf '%s: %s\n' "$program" "$*" >&2; }

# ---- Arguments --------------------------------------------------------------------------

url=""
out=""
robot=""
friction=""
validate=""
options="{}"
token=${MANIPID_TOKEN:-}
timeout=0
dir=""
while [[ $# -gt 0 ]]; do
  case "$1" in
    -h|--help) usage; exit 0 ;;
    --url|--out|--options|--token|--timeout|--robot|--friction|--validate)
      [[ $# -ge 2 ]] || die_usage "$1 needs a value"
      case "$1" in
        --url) url=$2 ;;
        --out) out=$2 ;;
        --options) options=$2 ;;
        --robot) robot=$2 ;;
        --friction) friction=$2 ;;
        --validate) validate=$2 ;;
        --token) token=$2 ;;
        --timeout) timeout=$2 ;;
      esac
      shift 2 ;;
    --url=*) url=${1#*=}; shift ;;
    --out=*) out=${1#*=}; shift ;;
    --options=*) options=${1#*=}; shift ;;
    --robot=*) robot=${1#*=}; shift ;;
    --friction=*) friction=${1#*=}; shift ;;
    --validate=*) validate=${1#*=}; shift ;;
    --token=*) token=${1#*=}; shift ;;
    --timeout=*) timeout=${1#*=}; shift ;;
    --) shift; [[ $# -eq 1 ]] || die_usage "expected one folder after --"; dir=$1; shift ;;
    -*) die_usage "unknown option '$1'" ;;
    *) [[ -z "$dir" ]] || die_usage "expected one folder, got '$dir' and '$1'"; dir=$1; shift ;;
  esac
done

for tool in curl jq sha256sum mktemp; do
  command -v "$tool" >/dev/null 2>&1 || { log "needs '$tool' on PATH"; exit 2; }
done
[[ -n "$url" ]] || die_usage "--url is required"
[[ -n "$out" ]] || die_usage "--out is required"
[[ -n "$dir" ]] || die_usage "the folder of CSV files is required"
[[ -d "$dir" ]] || die_usage "'$dir' is not a folder"
[[ "$timeout" =~ ^[0-9]+$ ]] || die_usage "--timeout must be a whole number of seconds, got '$timeout'"
url=${url%/}
[[ "$url" =~ ^https?:// ]] || die_usage "--url must start with http:// or https://, got '$url'"
if ! options=$(jq -cS 'if type == "object" then . else error("not an object") end' <<<"$options" 2>/dev/null); then
  die_usage "--options must be a JSON object, e.g. '{\"band\": 0.2}'"
fi
if [[ -z "$robot" ]]; then
  [[ -z "$friction" ]] || die_usage "--friction needs --robot (the paper's preset has no friction)"
  [[ -z "$validate" ]] || die_usage "--validate needs --robot"
else
  [[ -f "$robot" && -r "$robot" ]] || die_usage "--robot: cannot read the URDF '$robot'"
  [[ -z "$validate" || ( -f "$validate" && -r "$validate" ) ]] || die_usage "--validate: cannot read '$validate'"
  if [[ -n "$friction" ]]; then
    [[ "$friction" =~ ^[a-z]+(,[a-z]+)*$ ]] || die_usage "--friction: terms separated by commas, e.g. viscous,coulomb, got '$friction'"
    # "none" is no friction at all: the empty array; "auto" is chosen by held-out prediction.
    options=$(jq -cS --arg terms "$friction" \
      '. + {friction: (if $terms == "auto" then "auto" else ($terms | split(",") | if . == ["none"] then [] else . end) end)}' <<<"$options")
  fi
fi

out_dir=$(dirname -- "$out")
mkdir -p -- "$out_dir" 2>/dev/null || true
[[ -d "$out_dir" && -w "$out_dir" ]] || die_usage "cannot write the summary into '$out_dir'"

work=$(mktemp -d "${TMPDIR:-/tmp}/manipid-batch.XXXXXX")
trap 'rm -rf -- "$work"' EXIT

# The token goes to curl in a header file, never on its command line (visible in ps).
headers="$work/headers"
: >"$headers"
chmod 600 "$headers"
[[ -z "$token" ]] || printf 'Authorization: Bearer %s\n' "$token" >"$headers"

# ---- HTTP -------------------------------------------------------------------------------

# api METHOD PATH [curl arguments...]: sets $status (HTTP status, 000 when no answer) and
# $body (the answer). Retries what is safe to retry: every POST carries an Idempotency-Key.
status=""
body=""
api() {
  local method=$1 path=$2
  shift 2
  local curl_status=0
  status=$(curl -sS -X "$method" -H @"$headers" -o "$work/body" -D "$work/answer-headers" -w '%{http_code}' \
                --connect-timeout 10 --max-time 300 --retry 3 --retry-max-time 60 \
                "$@" --url "$url$path" 2>"$work/curl-error") || curl_status=$?
  body=$(cat "$work/body" 2>/dev/null || true)
  if [[ $curl_status -ne 0 ]]; then
    status=000
    body=$(printf '{"code":"CURL","detail":%s}' "$(jq -Rs 'rtrimstr("\n")' <"$work/curl-error")")
  fi
}

# replayed: " (existing)" when the last answer was an Idempotency-Key replay.
replayed() {
  if grep -qi '^Idempotent-Replayed: *true' "$work/answer-headers" 2>/dev/null; then printf ' (existing)'; fi
}

# problem: the reason from a problem+json body (or whatever came back) on one line.
problem() {
  jq -r --arg status "$status" '
      if type == "object" and has("code") then
        "\(.code)" + (if .field then " (field \(.field))" else "" end) + ": " + (.detail // .title // "" | tostring)
      else "HTTP \($status): \(tostring)" end' <<<"$body" 2>/dev/null \
    || printf 'HTTP %s: %s' "$status" "$(head -c 300 <<<"$body" | tr '\n' ' ')"
}

# Fail fast on a wrong URL or token, before any upload.
api GET "/v1/jobs?page_size=1"
if [[ "$status" != 200 ]]; then
  log "cannot use the service at $url: $(problem)"
  exit 1
fi

# ---- The robot and the validation run (uploaded once) -----------------------------------

# upload_dataset FILE: sets $dataset_id and $dataset_note, or returns 1 ($status, $body say why).
# The key is the file's SHA-256: the same file is the same dataset on every run.
upload_dataset() {
  local file=$1 content_hash
  content_hash=$(sha256sum <"$file" | cut -d' ' -f1) || return 1
  api POST "/v1/datasets?name=$(jq -rn --arg name "${file##*/}" '$name | @uri')" -H 'Content-Type: text/csv' \
      -H "Idempotency-Key: batch-ds-$content_hash" --data-binary @"$file"
  [[ "$status" == 201 ]] || return 1
  dataset_id=$(jq -r .id <<<"$body")
  dataset_note=$(replayed)
}

robot_id=""
validation_id=""
if [[ -n "$robot" ]]; then
  robot_hash=$(sha256sum <"$robot" | cut -d' ' -f1)
  api POST /v1/robots -H 'Content-Type: application/xml' -H "Idempotency-Key: batch-rb-$robot_hash" \
      --data-binary @"$robot"
  if [[ "$status" != 201 ]]; then
    log "${robot##*/}: robot upload failed: $(problem)"
    exit 1
  fi
  robot_id=$(jq -r .id <<<"$body")
  log "${robot##*/}: robot $robot_id$(replayed), $(jq -r '"\(.joints | length) joints \(.base_link) .. \(.tip_link)"' <<<"$body")"
  if [[ -n "$validate" ]]; then
    if ! upload_dataset "$validate"; then
      log "${validate##*/}: validation run upload failed: $(problem)"
      exit 1
    fi
    validation_id=$dataset_id
    log "${validate##*/}: validation run $validation_id$dataset_note"
  fi
  options=$(jq -cS --arg robot "$robot_id" --arg validation "$validation_id" \
               '. + {robot_id: $robot} + (if $validation != "" then {validation_dataset_id: $validation} else {} end)' \
               <<<"$options")
fi

# ---- Files ------------------------------------------------------------------------------

out_real=$(realpath -m -- "$out")
validate_real=""
[[ -z "$validate" ]] || validate_real=$(realpath -m -- "$validate")
files=()
while IFS= read -r -d '' file; do
  # Never upload a summary this script wrote (--out inside DIR, or one from an earlier run).
  [[ "$(realpath -m -- "$file")" == "$out_real" ]] && continue
  # The validation run is predicted, not identified.
  [[ -n "$validate_real" && "$(realpath -m -- "$file")" == "$validate_real" ]] && continue
  if [[ "$(head -c 24 -- "$file" 2>/dev/null)" == '"file","job_id","state",' ]]; then
    log "${file##*/}: skipped (a batch summary, not a trajectory)"
    continue
  fi
  files+=("$file")
done < <(find "$dir" -mindepth 1 -maxdepth 1 -type f -name '*.csv' -print0 | LC_ALL=C sort -z)
if [[ ${#files[@]} -eq 0 ]]; then
  log "no *.csv files in '$dir'"
  exit 1
fi

# Per file i: names[i] (as written in the summary), job_ids[i], states[i], errors[i];
# $work/job.i.json holds the last answer for the job.
names=() job_ids=() states=() errors=()
failures=0
for i in "${!files[@]}"; do
  file=${files[$i]}
  names[i]=${file##*/}
  job_ids[i]=""
  states[i]=""
  errors[i]=""
  if [[ ! -r "$file" ]] || ! file_hash=$(sha256sum <"$file" | cut -d' ' -f1); then
    states[i]=upload_failed
    errors[i]="cannot read the file"
    log "${names[i]}: ${errors[i]}"
    failures=$((failures + 1))
    continue
  fi

  if ! upload_dataset "$file"; then
    states[i]=upload_failed
    errors[i]=$(problem)
    log "${names[i]}: upload failed: ${errors[i]}"
    failures=$((failures + 1))
    continue
  fi

  # The key: the file's hash and the hash of the request (the options, normalised, with the
  # dataset id and any robot and validation ids — a dataset deleted and uploaded again gets a
  # new id, so a new job).
  request=$(jq -cS --arg id "$dataset_id" '. + {dataset_id: $id}' <<<"$options")
  request_hash=$(printf '%s' "$request" | sha256sum | cut -d' ' -f1)
  api POST /v1/identifications -H 'Content-Type: application/json' \
      -H "Idempotency-Key: batch-id-$file_hash-$request_hash" --data-binary "$request"
  if [[ "$status" != 202 ]]; then
    states[i]=submit_failed
    errors[i]=$(problem)
    log "${names[i]}: identification refused: ${errors[i]}"
    failures=$((failures + 1))
    continue
  fi
  job_ids[i]=$(jq -r .id <<<"$body")
  job_note=$(replayed)
  states[i]=$(jq -r .state <<<"$body")
  printf '%s\n' "$body" >"$work/job.$i.json"
  log "${names[i]}: dataset $dataset_id$dataset_note, job ${job_ids[i]}$job_note: ${states[i]}"
done

# ---- Wait -------------------------------------------------------------------------------

terminal() { [[ "$1" == succeeded || "$1" == failed || "$1" == cancelled ]]; }
started=$SECONDS
patience=5
for i in "${!files[@]}"; do
  [[ -n "${job_ids[i]}" ]] || continue
  misses=0
  while ! terminal "${states[i]}"; do
    wait_s=30
    if [[ $timeout -gt 0 ]]; then
      left=$((timeout - (SECONDS - started)))
      [[ $left -gt 0 ]] || break
      [[ $left -ge $wait_s ]] || wait_s=$left
    fi
    api GET "/v1/jobs/${job_ids[i]}?wait=$wait_s"
    if [[ "$status" == 200 ]]; then
      misses=0
      printf '%s\n' "$body" >"$work/job.$i.json"
      states[i]=$(jq -r .state <<<"$body")
    else
      # No answer or a busy server: try again a few times (curl has retried already), then
      # leave the job to a re-run; any other answer (404: deleted) is final.
      log "${names[i]}: polling ${job_ids[i]}: $(problem)"
      misses=$((misses + 1))
      if [[ ! "$status" =~ ^(000|429|502|503|504)$ || $misses -ge $patience ]]; then
        errors[i]=$(problem)
        [[ "$status" != 000 ]] || patience=1  # the service is gone: do not wait as long for the next
        break
      fi
      sleep 5
    fi
  done
  case "${states[i]}" in
    succeeded) ;;
    failed|cancelled)
      errors[i]=$(jq -r '.error // {} | if .code then "\(.code)" + (if .field then " (field \(.field))" else "" end) + ": \(.detail // "")" else "" end' \
                    "$work/job.$i.json")
      [[ -n "${errors[i]}" ]] || errors[i]="job ${states[i]}"
      log "${names[i]}: job ${job_ids[i]} ${states[i]}: ${errors[i]}"
      failures=$((failures + 1)) ;;
    *)
      [[ -n "${errors[i]}" ]] || errors[i]="still ${states[i]} after ${timeout} s; run the script again to collect it"
      log "${names[i]}: job ${job_ids[i]}: ${errors[i]}"
      failures=$((failures + 1)) ;;
  esac
done

# ---- Summary ----------------------------------------------------------------------------

# Parameter columns: every name any result has, in the order the service gives them (the
# preset's estimates by name; a robot's base parameters, whose names are their combinations).
names_filter='.result.estimates // {} | keys_unsorted[]'
[[ -z "$robot" ]] || names_filter='.result.base_parameters // [] | .[].name'
parameters='[]'
for i in "${!files[@]}"; do
  [[ -f "$work/job.$i.json" ]] || continue
  parameters=$(jq -c --argjson seen "$parameters" "\$seen + ([$names_filter] - \$seen)" "$work/job.$i.json")
done

summary="$work/summary.csv"
if [[ -z "$robot" ]]; then
  jq -nr --argjson p "$parameters" '["file", "job_id", "state"] + $p + ["final_cost", "error"] | @csv' >"$summary"
else
  jq -nr --argjson p "$parameters" \
     '["file", "job_id", "state", "fit_relative_error", "validation_relative_error"] + $p + ["error"] | @csv' >"$summary"
fi
for i in "${!files[@]}"; do
  job_json="$work/job.$i.json"
  [[ -f "$job_json" ]] || printf '{}\n' >"$job_json"
  if [[ -z "$robot" ]]; then
    row='(.result // {}) as $r
         | [$file, $job, $state] + [$p[] as $name | $r.estimates[$name]?] + [$r.final_cost, $error]'
  else
    row='(.result // {}) as $r
         | ([$r.base_parameters[]? | {key: .name, value: .estimate}] | from_entries) as $b
         | [$file, $job, $state, $r.fit.overall_relative_error, $r.validation.overall_relative_error]
           + [$p[] as $name | $b[$name]] + [$error]'
  fi
  jq -r --argjson p "$parameters" --arg file "${names[i]}" --arg job "${job_ids[i]}" \
        --arg state "${states[i]}" --arg error "${errors[i]}" "$row | @csv" "$job_json" >>"$summary"
done
cp -- "$summary" "$out"

succeeded=$(( ${#files[@]} - failures ))
log "${succeeded} of ${#files[@]} succeeded; summary in $out"
[[ $failures -eq 0 ]]
