#!/usr/bin/env bash
# Builds manipid with AddressSanitizer and UndefinedBehaviorSanitizer (the `debug` preset)
# and runs every test: unit tests of core/, api/ and the store, the command line and the
# service end to end (the real binary on port 0 with a real SQLite file), the Python and
# MATLAB/Octave clients, the curl batch script and the packaging checks — then fuzzes the
# JSON and CSV request parsers on a fixed count of generated inputs from a fixed seed
# (scripts/fuzz.sh --runs; open-ended random fuzzing is `scripts/fuzz.sh SECONDS`).
# Installs missing Debian packages first. Usage: bash scripts/test.sh [FUZZ_INPUTS_PER_TARGET]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash scripts/setup.sh
cmake --preset debug >/dev/null
cmake --build --preset debug -j "$(nproc)"
ctest --preset debug -j "$(nproc)"
bash scripts/fuzz.sh --runs "${1:-60000}"
