#!/usr/bin/env bash
# Builds and runs one of the benchmark programs (each prints Markdown tables; every frame
# benchmark follows the rules of Benchmarks/Harness.h: every contender in VTK's default
# window (multisampled) and single-sampled, ratios taking each mapper in its faster window,
# the camera turning before every timed frame, medians, stages apart from the frame).
#
# Usage: scripts/figures/benchmark.sh PROGRAM [arguments...]
#   core      mtpt_bench_core: the core's CPU stages, visibility orders against library sorts
#   frames    mtpt_bench_frames: whole frames, MTPT's backends against VTK's mappers
#   scaling   mtpt_bench_scaling: frame time against mesh size or window size, with a plot
#   accuracy  mtpt_bench_accuracy: speed against error, every mapper against the exact integral
#   work      mtpt_bench_work: culling, reuse, batching, peak memory
#   interactive  mtpt_bench_interactive: moving frames at an asked rate, time and error
#   large     mtpt_bench_large: 1M to 100M tetrahedra, frames, stages and memory, with a plot
#   volumes   mtpt_bench_volumes: two volumes of n/2 tetrahedra in one order against one of n
# Real meshes beyond the repository's (comb, kiefer, pulley, fire_ug, ironProt) come from
# the folder in MTPT_DATA_DIR, when set; `--help` after the program name lists its options.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="${MTPT_BUILD_DIR:-$here/build}"
program="${1:-}"
case "$program" in
  core | frames | scaling | accuracy | work | interactive | large | volumes) shift ;;
  *)
    sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//' >&2
    exit 2
    ;;
esac
"$here/scripts/install/install-deps.sh" >/dev/null
cmake -S "$here" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" --parallel "$(nproc)" --target "mtpt_bench_$program"
if [ "$program" = core ]; then
  exec "$build/Benchmarks/mtpt_bench_core" "$@"
fi
exec "$here/Testing/xvfb-launch.sh" "$build/Benchmarks/mtpt_bench_$program" "$@"
