#!/usr/bin/env bash
# The project's test command: installs what is missing, builds (Release) and runs every
# test with ctest, then builds and tests the ParaView plugin (scripts/plugin.sh) unless
# MTPT_SKIP_PLUGIN=1.
# --shuffled runs the tests of the two gtest programs (ctest label `shuffled`) otherwise:
# each program whole, its tests in a random order (scripts/ci/shuffled-tests.sh), and the
# other tests with ctest, so every test still runs once.
# Usage: scripts/test.sh [--shuffled] [build-dir]   (default: build)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
shuffled=0
if [ "${1:-}" = --shuffled ]; then
  shuffled=1
  shift
fi
build="${1:-$here/build}"

# Inside the Debian unstable chroot (scripts/install/sid-chroot.sh) the packages are the chroot's.
if [ "${MTPT_IN_SID_CHROOT:-0}" != 1 ]; then
  "$here/scripts/install/install-deps.sh"
fi

jobs="$(nproc)"
cmake -S "$here" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build "$build" --parallel "$jobs"
# Render-window tests share one X server (Mesa llvmpipe) when there is no display; see
# Testing/xvfb-launch.sh for why -noreset.
run_ctest=(ctest --test-dir "$build" --output-on-failure --parallel "$jobs" --timeout 900)
if [ "$shuffled" = 1 ]; then
  run_ctest+=(--label-exclude shuffled)
fi
if [ -z "${DISPLAY:-}" ]; then
  xvfb-run -a -s "-screen 0 1024x768x24 -noreset" "${run_ctest[@]}"
else
  "${run_ctest[@]}"
fi
if [ "$shuffled" = 1 ]; then
  "$here/scripts/ci/shuffled-tests.sh" "$build"
fi

# The ParaView plugin, after the tests pass: its own build tree (<build-dir>-plugin) and its
# own headless tests (pvpython, pvbatch, 2-rank MPI pvbatch). MTPT_SKIP_PLUGIN=1 skips it.
if [ "${MTPT_SKIP_PLUGIN:-0}" != 1 ]; then
  "$here/scripts/plugin.sh" "${build%/}-plugin"
fi
