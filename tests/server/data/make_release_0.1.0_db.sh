#!/usr/bin/env bash
# make_release_0.1.0_db.sh — how tests/server/data/manipid-0.1.0.db was made: a database written by
# manipid 0.1.0 (commit 995a665, schema version 1) with every kind of row, for the migration test
# (tests/server/migration_test.cpp). Run once by hand with that release's binary; CI only reads the file.
#
#   git worktree add --detach /tmp/manipid-0.1.0 995a665 && cmake -S /tmp/manipid-0.1.0 -B /tmp/m010 \
#     -DMANIPID_BUILD_TESTS=OFF -DMANIPID_BUILD_BENCHMARKS=OFF && cmake --build /tmp/m010 --target manipid
#   bash tests/server/data/make_release_0.1.0_db.sh /tmp/m010/server/manipid
set -euo pipefail
manipid=$(realpath "${1:?usage: make_release_0.1.0_db.sh /path/to/manipid-0.1.0}")
out=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/manipid-0.1.0.db
work=$(mktemp -d)
trap 'kill "$server" 2>/dev/null || true; rm -rf "$work"' EXIT
cd "$work"

"$manipid" simulate --duration 1 --out run.csv 2>/dev/null
"$manipid" serve --port 0 --db fixture.db --workers 1 >port.txt 2>server.log &
server=$!
for _ in $(seq 100); do [[ -s port.txt ]] && break; sleep 0.1; done
url=$(awk '{print $3}' port.txt)

post() { curl -sf -H 'Content-Type: application/json' "$@"; }
dataset=$(curl -sf -H 'Content-Type: text/csv' --data-binary @run.csv "$url/v1/datasets?name=uploaded" | jq -r .id)
# A succeeded identification with a history and estimates, submitted with an Idempotency-Key.
identified=$(post -H 'Idempotency-Key: fixture-key' \
  -d "{\"dataset_id\": \"$dataset\", \"half_length\": 100, \"band\": 0.2, \"free\": [\"m2\", \"m3\"], \"max_evaluations\": 40}" \
  "$url/v1/identifications" | jq -r .id)
curl -sf "$url/v1/jobs/$identified?wait=30" >/dev/null
# A simulation job and the dataset it made.
simulated=$(post -d '{"duration": 0.5}' "$url/v1/simulations" | jq -r .id)
curl -sf "$url/v1/jobs/$simulated?wait=30" >/dev/null
# A failed identification (its dataset deleted before it ran) and a cancelled one behind a slow job.
slow=$(post -d "{\"dataset_id\": \"$dataset\", \"method\": \"output-error\", \"max_evaluations\": 200}" "$url/v1/identifications" | jq -r .id)
cancelled=$(post -d "{\"dataset_id\": \"$dataset\", \"half_length\": 100, \"band\": 0.2}" "$url/v1/identifications" | jq -r .id)
curl -sf -X POST "$url/v1/jobs/$cancelled/cancel" >/dev/null
curl -sf "$url/v1/jobs/$slow?wait=30" >/dev/null || true
curl -sf -X POST "$url/v1/jobs/$slow/cancel" >/dev/null
curl -sf "$url/v1/jobs/$slow?wait=30" >/dev/null
kill -TERM "$server"
wait "$server" || true
python3 -c "import sqlite3; c = sqlite3.connect('fixture.db'); c.execute('VACUUM'); c.close()"
cp fixture.db "$out"
echo "wrote $out: dataset $dataset, jobs $identified (succeeded), $simulated (simulation), $slow, $cancelled (cancelled)"
