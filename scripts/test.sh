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
# Render-window tests share one X server (Mesa llvmpipe) when there is no display; see
# Testing/xvfb-launch.sh for why -noreset.
if [ -z "${DISPLAY:-}" ]; then
  exec xvfb-run -a -s "-screen 0 1024x768x24 -noreset" \
    ctest --output-on-failure --parallel "$jobs" --timeout 900
fi
ctest --output-on-failure --parallel "$jobs" --timeout 900
