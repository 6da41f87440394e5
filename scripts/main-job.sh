#!/usr/bin/env bash
# The main job: builds manipid (release), starts the service on a free port with a fresh
# SQLite database, and runs the paper's case against it over HTTP — one request simulates the
# 4-DOF manipulator under PD control and identifies its parameters with the input-error
# method — then prints the estimates and stops the service.
# Installs missing Debian packages first. Usage: bash scripts/main-job.sh [OUTPUT_DIR]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
out=${1:-build/paper-case}
bash scripts/setup.sh
cmake --preset release >/dev/null
cmake --build --preset release -j "$(nproc)" --target manipid
mkdir -p "$out"
rm -f "$out/manipid.db" "$out/manipid.db-wal" "$out/manipid.db-shm"
manipid=build/release/server/manipid

# Start the service; its first line on stdout is "listening on http://HOST:PORT".
coproc server { exec "$manipid" serve --port 0 --db "$out/manipid.db" 2>"$out/server.log"; }
read -r -u "${server[0]}" first_line
url=${first_line##* }
trap 'kill "$server_PID" 2>/dev/null; wait "$server_PID" 2>/dev/null || true' EXIT
echo "== service: $url (database $out/manipid.db, log $out/server.log)"

echo "== POST /v1/identifications: the paper's experiment (simulate cedro2009, then identify)"
job=$(curl -sS --fail-with-body -H 'Content-Type: application/json' \
  -d '{"simulation": {"preset": "cedro2009"}, "preset": "cedro2009"}' "$url/v1/identifications")
id=$(python3 -c 'import json,sys; print(json.load(sys.stdin)["id"])' <<<"$job")
echo "   job $id queued; waiting"
until [[ $(python3 -c 'import json,sys; print(json.load(sys.stdin)["state"])' <<<"$job") =~ ^(succeeded|failed|cancelled)$ ]]; do
  job=$(curl -sS --fail-with-body "$url/v1/jobs/$id?wait=30")
done
printf '%s\n' "$job" >"$out/job.json"
curl -sS --fail-with-body -H 'Accept: text/csv' "$url/v1/jobs/$id/history" >"$out/history.csv"
curl -sS --fail-with-body "$url/v1/datasets/$(python3 -c 'import json,sys; print(json.load(sys.stdin)["dataset_id"])' <<<"$job")?format=csv" >"$out/run.csv"
python3 scripts/print_result.py "$out/job.json"
echo "== saved: $out/job.json (the job), $out/history.csv (every evaluation), $out/run.csv (the data)"
echo "== to look at it in the dashboard: $manipid serve --db $out/manipid.db"
echo "   then open http://127.0.0.1:8080/jobs/$id"
