#!/usr/bin/env bash
# The project's test command: installs what is missing, builds (Release) and runs every
# test with ctest. Usage: scripts/test.sh [build-dir]   (default: build)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:-$here/build}"

"$here/scripts/install-deps.sh"

jobs="$(nproc)"
cmake -S "$here" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build "$build" --parallel "$jobs"
cd "$build"
ctest --output-on-failure --parallel "$jobs" --timeout 900
