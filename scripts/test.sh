#!/usr/bin/env bash
# Builds manipid with AddressSanitizer and UndefinedBehaviorSanitizer (the `debug` preset)
# and runs every test: unit tests of core/ and api/, and the command line end to end.
# Installs missing Debian packages first. Usage: bash scripts/test.sh
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash scripts/setup.sh
cmake --preset debug >/dev/null
cmake --build --preset debug -j "$(nproc)"
ctest --preset debug -j "$(nproc)"
