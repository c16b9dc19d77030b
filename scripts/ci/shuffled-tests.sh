#!/usr/bin/env bash
# The suite in any order: each gtest program of a build run in few processes, each running
# many tests, in the order of --gtest_shuffle by a random seed printed first, so that a test
# that leans on state another test left (a global VTK setting, a cache) fails here although
# ctest, one process per test, passes it. Rerun a failure's order with --seed (and the same
# --shards). The soak program (mtpt_rendering_soak) holds a single test, which ctest already
# runs whole in one process: it has no order to shuffle and is left out.
#
# Each program's tests are split into --shards parts (gtest's GTEST_TOTAL_SHARDS, default:
# the number of cores), run side by side, one process each, each part in its own shuffled
# order: the cores all work, and each process still runs dozens of tests one after another.
# --shards 1 runs each program whole in one process.
# Usage: scripts/ci/shuffled-tests.sh [build-dir] [--runs N] [--seed S] [--shards K]
#        (default: build, 1 run, K = nproc)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
. "$here/scripts/ci/gtest-shards.sh"
build="$here/build"
runs=1
seed=""
shards="$(nproc)"
while [ $# -gt 0 ]; do
  case "$1" in
  --runs) runs="$2"; shift 2 ;;
  --seed) seed="$2"; shift 2 ;;
  --shards) shards="$2"; shift 2 ;;
  *) build="$1"; shift ;;
  esac
done
[[ "$shards" =~ ^[1-9][0-9]*$ ]] || { echo "shuffled-tests: --shards takes a count >= 1" >&2; exit 2; }
build="$(cd "$build" && pwd)" || { echo "shuffled-tests: no build tree $build" >&2; exit 1; }
# The programs whose tests carry the ctest label `shuffled` (Testing/ShuffledLabel.cmake):
# scripts/test.sh --shuffled runs their tests here and nowhere else, so the two lists agree.
programs=("$build/Testing/Core/mtpt_core_tests" "$build/Testing/Rendering/mtpt_rendering_tests")
for program in "${programs[@]}"; do
  [ -x "$program" ] || { echo "shuffled-tests: no $program (scripts/test.sh builds it)" >&2; exit 1; }
done
cd "$build" # as ctest runs them: output files land in the build tree
for run in $(seq "$runs"); do
  for program in "${programs[@]}"; do
    name="$(basename "$program")"
    s="${seed:-$((RANDOM * 32768 + RANDOM))}"
    echo "shuffled-tests: run $run of $runs: $name --gtest_shuffle --gtest_random_seed=$s" \
      "in $shards shards"
    started=$(date +%s)
    run_gtest_shards "$shards" "$build/shuffled-$name" "$here/Testing/xvfb-launch.sh" \
      "$program" --gtest_shuffle --gtest_random_seed="$s" --gtest_brief=1
    for shard in $(seq 0 $((shards - 1))); do
      echo "  shard $shard: $(grep -E '^\[  (PASSED|FAILED)  \] [0-9]+ tests?' \
        "$build/shuffled-$name-$shard.log" | tr '\n' ' ')"
    done
    if [ ${#failed_shards[@]} -gt 0 ]; then
      for shard in "${failed_shards[@]}"; do
        log="$build/shuffled-$name-$shard.log"
        grep -E '^\[  FAILED  \] [A-Za-z]' "$log" | sort -u || tail -n 20 "$log"
        echo "shuffled-tests: $name shard $shard of $shards FAILED with seed $s (log: $log;" \
          "again: scripts/ci/shuffled-tests.sh --seed $s --shards $shards)"
      done
      exit 1
    fi
    echo "shuffled-tests: passed in $(($(date +%s) - started)) s"
  done
done
