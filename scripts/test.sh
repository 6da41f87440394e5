#!/usr/bin/env bash
# Builds manipid with AddressSanitizer and UndefinedBehaviorSanitizer (the `debug` preset)
# and runs every test: unit tests of core/, api/ and the store, the command line and the
# service end to end (the real binary on port 0 with a real SQLite file), the Python and
# MATLAB/Octave clients, the curl batch script and the packaging checks, and the HTTP fuzz
# target's saved inputs (the parsers' fuzz targets build meanwhile, at the lowest priority) —
# then fuzzes the JSON, CSV and ROS 2 bag parsers on a fixed count of generated inputs from a fixed
# seed (scripts/fuzz.sh --runs; open-ended random fuzzing of all four targets, the HTTP route
# layer too, is `scripts/fuzz.sh SECONDS`).
# Installs missing Debian packages first. Usage: bash scripts/test.sh [FUZZ_INPUTS_PER_TARGET]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash scripts/setup.sh
cmake --preset debug >/dev/null
# One job more than processors: a compile waiting on the disk or a link leaves a processor idle.
cmake --build --preset debug -j "$(( $(nproc) + 1 ))"
# The fuzz targets are built while the tests run, at the lowest priority: many tests wait on
# servers, browsers and timers, and the build takes only the processor time they leave.
mkdir -p build
export FUZZ_TARGETS="json_fuzz csv_fuzz bag_fuzz"
nice -n 19 bash scripts/fuzz.sh --build-only >build/fuzz-build.log 2>&1 &
fuzz_build=$!
tests=0
ctest --preset debug -j "$(nproc)" || tests=$?
if ! wait "$fuzz_build"; then
  cat build/fuzz-build.log >&2
  echo "test.sh: the fuzz targets did not build (log above)" >&2
  exit 1
fi
tail -1 build/fuzz-build.log
[[ "$tests" -eq 0 ]] || exit "$tests"
bash scripts/fuzz.sh --runs "${1:-30000}"
