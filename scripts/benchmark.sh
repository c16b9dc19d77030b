#!/usr/bin/env bash
# Builds and runs the core-stage benchmark; prints Markdown tables. Extra arguments go to
# mtpt_bench_core (e.g. --quick, --tets N, --repeat R, --threads 1,2).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${MTPT_BUILD_DIR:-$here/build}"
"$here/scripts/install-deps.sh"
cmake -S "$here" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" --parallel "$(nproc)" --target mtpt_bench_core
"$build/Benchmarks/mtpt_bench_core" --data "$here/../shared/data" "$@"
