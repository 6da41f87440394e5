#!/usr/bin/env bash
# Builds the libFuzzer targets of tests/fuzz/ (JSON, CSV and ROS 2 bag parsers of api/; raw HTTP
# bytes into the server's route layer, http_fuzz) with clang, ASan and UBSan into build/fuzz,
# and fuzzes each on a copy of its seed corpus
# (build/fuzz/corpus-<target>; the repository's corpus is never modified), together with the
# reproducers kept in tests/fuzz/regressions/<target>/. Targets run side by side when there
# are at least two CPUs. Prints one summary line per target; exits non-zero if any target
# crashes, leaks, times out or runs out of memory (the input is saved as
# build/fuzz/artifacts-<target>/crash-*, oom-*, leak-* or timeout-*).
#
#   bash scripts/fuzz.sh [SECONDS]   explore: a random seed, SECONDS per target (default 20)
#   bash scripts/fuzz.sh --runs N    check: seed 1, exactly N inputs per target (N / 4 for
#                                    http_fuzz, whose inputs each take a socket round trip) — for
#                                    the same build and corpus the same inputs, so a red result
#                                    points at the code, not the luck of the draw (what
#                                    scripts/test.sh runs; coverage figures still vary a little
#                                    between machines, and more for http_fuzz, whose server
#                                    threads interleave differently from run to run)
# FUZZ_TARGETS (environment) names the targets to build and run, default all four; the test
# command (scripts/test.sh) fuzzes the parsers only ("json_fuzz csv_fuzz bag_fuzz": building http_fuzz
# costs 5 minutes of CPU) and replays http_fuzz's saved inputs in the main build instead (ctest
# http_fuzz_replay).
# Installs nothing: run scripts/setup.sh first (needs the Debian packages clang and
# libclang-rt-14-dev).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

usage="usage: scripts/fuzz.sh [SECONDS_PER_TARGET] | --runs INPUTS_PER_TARGET | --build-only"
build_only=false
if [[ "${1:-}" == "--build-only" ]]; then
  # Only build the targets (scripts/test.sh builds them while the tests run).
  build_only=true
  count=1
  describe=""
elif [[ "${1:-}" == "--runs" ]]; then
  mode=runs
  count=${2:-}
  describe="$count inputs per target (http_fuzz: a quarter), seed 1"
else
  mode=seconds
  count=${1:-20}
  describe="$count s per target, random seed"
fi
if ! [[ "$count" =~ ^[1-9][0-9]*$ ]]; then
  echo "$usage  (a positive whole number, got '$count')" >&2
  exit 2
fi
command -v clang++ >/dev/null || { echo "fuzz: clang++ not found; run scripts/setup.sh" >&2; exit 2; }

build=build/fuzz
jobs=$(nproc)
started=$SECONDS
CC=clang CXX=clang++ cmake -S tests/fuzz -B "$build" >/dev/null
selected=${FUZZ_TARGETS:-json_fuzz csv_fuzz bag_fuzz http_fuzz}
# shellcheck disable=SC2086  # one target per word
cmake --build "$build" -j "$jobs" --target $selected
if $build_only; then
  echo "== fuzz: built in $((SECONDS - started)) s"
  exit 0
fi
echo "== fuzz: built in $((SECONDS - started)) s; fuzzing: $describe"

# target, corpus and dictionary name, longest input in bytes, share of --runs N (N / share):
# an http_fuzz input is a connection to a server thread, several times a parser call's cost
# (its longest input holds a request line over cpp-httplib's 8192-byte limit).
targets=()
for entry in "json_fuzz json 4096 1" "csv_fuzz csv 4096 1" "bag_fuzz bag 16384 1" "http_fuzz http 10000 4"; do
  [[ " $selected " == *" ${entry%% *} "* ]] && targets+=("$entry")
done

run_target() {
  local target=$1 name=$2 max_len=$3 share=$4
  local budget=(-max_total_time="$count")
  if [[ "$mode" == runs ]]; then budget=(-seed=1 -runs=$((count / share > 0 ? count / share : 1))); fi
  local corpus=$build/corpus-$target artifacts=$build/artifacts-$target
  rm -rf "$corpus" "$artifacts"
  mkdir -p "$corpus" "$artifacts"
  cp tests/fuzz/corpus/"$name"/* "$corpus"/
  local inputs=("$corpus")
  local regressions=tests/fuzz/regressions/$target
  if [[ -d "$regressions" ]] && compgen -G "$regressions/*" >/dev/null; then inputs+=("$regressions"); fi
  # The first directory receives the new units; the others (regressions) are only read.
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 "$build/$target" \
    "${budget[@]}" -timeout=5 -rss_limit_mb=2048 -max_len="$max_len" \
    -dict=tests/fuzz/"$name".dict -artifact_prefix="$artifacts"/ -print_final_stats=1 \
    "${inputs[@]}" >"$build/$target.log" 2>&1
}

summarize() {
  local target=$1 status=$2 log=$build/$1.log
  local execs rate cov ft corpus rss
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  rss=$(sed -n 's/^stat::peak_rss_mb: *//p' "$log" | tail -1)
  # The last progress line ("#12345 DONE cov: 1234 ft: 5678 corp: 90/12Kb ...") has the coverage.
  local progress
  progress=$(grep -E '^#[0-9]+.*cov: [0-9]+' "$log" | tail -1 || true)
  cov=$(sed -nE 's/.*cov: ([0-9]+).*/\1/p' <<<"$progress")
  ft=$(sed -nE 's/.* ft: ([0-9]+).*/\1/p' <<<"$progress")
  corpus=$(sed -nE 's/.* corp: ([0-9]+\/[0-9]+[a-zA-Z]*).*/\1/p' <<<"$progress")
  local verdict=ok
  [[ "$status" -eq 0 ]] || verdict="FAILED (exit $status; log $log)"
  printf '%-10s %10s execs  %7s exec/s  cov %-5s ft %-6s corpus %-12s peak RSS %s MB  %s\n' \
    "$target" "${execs:-?}" "${rate:-?}" "${cov:-?}" "${ft:-?}" "${corpus:-?}" "${rss:-?}" "$verdict"
}

declare -A status
if [[ "$jobs" -ge 2 ]]; then
  declare -A pid
  for entry in "${targets[@]}"; do
    read -r target name max_len share <<<"$entry"
    run_target "$target" "$name" "$max_len" "$share" &
    pid[$target]=$!
  done
  for entry in "${targets[@]}"; do
    read -r target _ _ _ <<<"$entry"
    if wait "${pid[$target]}"; then status[$target]=0; else status[$target]=$?; fi
  done
else
  for entry in "${targets[@]}"; do
    read -r target name max_len share <<<"$entry"
    if run_target "$target" "$name" "$max_len" "$share"; then status[$target]=0; else status[$target]=$?; fi
  done
fi

failed=0
echo "== fuzz: results (execs, exec/s, edge coverage, features, corpus units/bytes)"
for entry in "${targets[@]}"; do
  read -r target _ _ _ <<<"$entry"
  summarize "$target" "${status[$target]}"
  if [[ "${status[$target]}" -ne 0 ]]; then
    failed=1
    # The sanitizer's report and the saved input.
    grep -E -A40 '^[a-z]+_fuzz: |^==[0-9]+==ERROR|runtime error|^SUMMARY|deadly signal|Test unit written' "$build/$target.log" | head -60 >&2 || true
  fi
done
exit "$failed"
