#!/usr/bin/env bash
# The suite in any order: each gtest program of a build run whole, in one process, with its
# tests shuffled (--gtest_shuffle) by a random seed printed first, so that a test that leans
# on state another test left (a global VTK setting, a cache) fails here although ctest, one
# process per test, passes it. Rerun a failure's order with --seed.
# Usage: scripts/ci/shuffled-tests.sh [build-dir] [--runs N] [--seed S]   (default: build, 1 run)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="$here/build"
runs=1
seed=""
while [ $# -gt 0 ]; do
  case "$1" in
  --runs) runs="$2"; shift 2 ;;
  --seed) seed="$2"; shift 2 ;;
  *) build="$1"; shift ;;
  esac
done
build="$(cd "$build" && pwd)" || { echo "shuffled-tests: no build tree $build" >&2; exit 1; }
programs=("$build/Testing/Core/mtpt_core_tests" "$build/Testing/Rendering/mtpt_rendering_tests"
  "$build/Testing/Rendering/mtpt_rendering_soak")
for program in "${programs[@]}"; do
  [ -x "$program" ] || { echo "shuffled-tests: no $program (scripts/test.sh builds it)" >&2; exit 1; }
done
cd "$build" # as ctest runs them: output files land in the build tree
for run in $(seq "$runs"); do
  for program in "${programs[@]}"; do
    s="${seed:-$((RANDOM * 32768 + RANDOM))}"
    echo "shuffled-tests: run $run of $runs: $(basename "$program") --gtest_shuffle --gtest_random_seed=$s"
    started=$(date +%s)
    status=0
    "$here/Testing/xvfb-launch.sh" "$program" --gtest_shuffle --gtest_random_seed="$s" \
      --gtest_brief=1 >"$build/shuffled-$(basename "$program").log" 2>&1 || status=$?
    tail -n 3 "$build/shuffled-$(basename "$program").log"
    if [ "$status" != 0 ]; then
      grep -E '^\[  FAILED  \]' "$build/shuffled-$(basename "$program").log" | sort -u || true
      echo "shuffled-tests: $(basename "$program") FAILED with seed $s (log:" \
        "$build/shuffled-$(basename "$program").log; again: scripts/ci/shuffled-tests.sh --seed $s)"
      exit 1
    fi
    echo "shuffled-tests: passed in $(($(date +%s) - started)) s"
  done
done
