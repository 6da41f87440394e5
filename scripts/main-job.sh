#!/usr/bin/env bash
# The main job: builds manipid (release) and runs the paper's case — simulate the 4-DOF
# manipulator under PD control, then identify its parameters with the input-error method.
# Installs missing Debian packages first. Usage: bash scripts/main-job.sh [OUTPUT_DIR]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
out=${1:-build/paper-case}
bash scripts/setup.sh
cmake --preset release >/dev/null
cmake --build --preset release -j "$(nproc)" --target manipid
mkdir -p "$out"
manipid=build/release/server/manipid
echo "== simulate: the paper's run (cedro2009, complete kinetic energy) -> $out/run.csv"
"$manipid" simulate --preset cedro2009 --out "$out/run.csv"
echo "== identify: input-error, filter chosen from the data, the paper's start values"
"$manipid" identify "$out/run.csv" --preset cedro2009 --history "$out/history.csv"
