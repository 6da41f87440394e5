#!/usr/bin/env bash
# run_tests.sh — the MATLAB/Octave client against a real `manipid serve`, with GNU Octave.
#
# Starts `manipid serve --port 0` on a temporary database (with a bearer token, so the
# Authorization header is exercised), writes the paper's run with `manipid simulate` and a
# URDF robot's runs with `manipid excitation` and `manipid torque` (examples/robots/
# panda_like.urdf, a known truth; run.csv noise-free, check.csv with 1 % torque noise, tool.csv with a
# tool on the tip link), runs
# clients/matlab/tests/run_tests.m in octave-cli, stops the server (SIGTERM, expects exit 0)
# and exits non-zero on any failure.
#
# Usage: clients/matlab/tests/run_tests.sh [MANIPID_BIN]
#   binary: the argument, else $MANIPID_BIN, else build/release/server/manipid
#   OCTAVE: the Octave command (default octave-cli)
# Exit status: 0 passed, 1 failed, 2 no binary, 77 no Octave (skipped).
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../../.." && pwd)
binary=${1:-${MANIPID_BIN:-$root/build/release/server/manipid}}
octave=${OCTAVE:-octave-cli}

if [[ ! -x "$binary" ]]; then
  echo "run_tests.sh: no manipid binary at $binary (pass it or set MANIPID_BIN)" >&2
  exit 2
fi
if ! command -v "$octave" > /dev/null; then
  echo "run_tests.sh: SKIPPED: $octave not found (apt-get install --no-install-recommends octave)" >&2
  exit 77   # CTest SKIP_RETURN_CODE
fi

work=$(mktemp -d "${TMPDIR:-/tmp}/manipid-matlab-test-XXXXXX")
server_pid=
cleanup() {
  if [[ -n "$server_pid" ]] && kill -0 "$server_pid" 2> /dev/null; then
    kill "$server_pid" 2> /dev/null || true
    wait "$server_pid" 2> /dev/null || true
  fi
  rm -rf "$work"
}
trap cleanup EXIT

token="octave-test-$RANDOM$RANDOM"
"$binary" simulate --out "$work/run.csv" 2> /dev/null

# The robot's runs: link 3 heavier and joint 2 with more friction than the URDF says.
urdf="$root/examples/robots/panda_like.urdf"
mkdir -p "$work/robot"
echo '{"m3": 3.0, "fv2": 0.4, "fc2": 0.7, "fo3": 0.05}' > "$work/robot/truth.json"
"$binary" excitation --robot "$urdf" --period 10 --harmonics 5 --duration 20 --max-evaluations 300 --seed 1 \
  --out "$work/robot/excitation.csv" 2> /dev/null
"$binary" torque --robot "$urdf" --params "$work/robot/truth.json" --with-states --in "$work/robot/excitation.csv" \
  --out "$work/robot/run.csv" 2> /dev/null
"$binary" torque --robot "$urdf" --params "$work/robot/truth.json" --with-states --in "$work/robot/excitation.csv" \
  --noise-tau-relative 0.01 --seed 2 --out "$work/robot/check.csv" 2> /dev/null
# A tool on the tip link (the clients' tests' own, clients/python/tests/robot_data.py): the URDF with the
# tool as a fixed link, the same motion and truth, and the tool's values for the test to compare with.
python3 - "$root/clients/python/tests" "$urdf" "$work/robot" <<'PYTHON'
import json, os, sys
sys.path.insert(0, sys.argv[1])
from robot_data import TOOL, tip_link, with_tool
document = open(sys.argv[2]).read()
with open(os.path.join(sys.argv[3], "tool.urdf"), "w") as stream:
    stream.write(with_tool(document, tip_link(document)))
with open(os.path.join(sys.argv[3], "tool.json"), "w") as stream:
    json.dump(TOOL, stream)
PYTHON
"$binary" torque --robot "$work/robot/tool.urdf" --params "$work/robot/truth.json" --with-states \
  --in "$work/robot/excitation.csv" --noise-tau-relative 0.01 --seed 3 --out "$work/robot/tool.csv" 2> /dev/null

# The first stdout line is "listening on http://HOST:PORT"; keep reading the pipe from a
# file descriptor so that the server never blocks on a full stdout.
mkfifo "$work/stdout"
"$binary" serve --port 0 --db "$work/jobs.db" --workers 2 --token "$token" \
  > "$work/stdout" 2> "$work/server.log" &
server_pid=$!
exec 3< "$work/stdout"
if ! IFS= read -r -t 30 line <&3 || [[ "$line" != "listening on http://"* ]]; then
  echo "run_tests.sh: the server did not start: '${line:-}'" >&2
  cat "$work/server.log" >&2
  exit 1
fi
cat <&3 > /dev/null &
url=${line##* }
echo "run_tests.sh: server $url (pid $server_pid), $($octave --version | head -n 1)"

status=0
MANIPID_URL="$url" MANIPID_RUN_CSV="$work/run.csv" MANIPID_TOKEN="$token" MANIPID_TEST_TOKEN=1 \
  MANIPID_URDF="$urdf" MANIPID_UR5="$root/examples/robots/ur5_like.urdf" MANIPID_ROBOT_DIR="$work/robot" \
  "$octave" --no-gui --norc --no-history --quiet \
  --eval "addpath('$here'); try, run_tests(); catch err, fprintf(2, '%s\n', err.message); exit(1); end" \
  || status=$?

kill -TERM "$server_pid"
server_status=0
wait "$server_pid" || server_status=$?
server_pid=
if [[ $status -ne 0 ]]; then
  echo "run_tests.sh: FAILED (octave exit $status); server log:" >&2
  tail -n 30 "$work/server.log" >&2
  exit 1
fi
if [[ $server_status -ne 0 ]]; then
  echo "run_tests.sh: the server exited $server_status on SIGTERM" >&2
  exit 1
fi
echo "run_tests.sh: passed"
