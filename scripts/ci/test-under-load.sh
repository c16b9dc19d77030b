#!/usr/bin/env bash
# Runs the soak test and the whole ctest suite of a build tree several times while busy
# loops compete for the cores, and prints a line per run: the suite must hold on a busy
# machine (Documentation/testing.md, "Tests under a competing load").
#
# Usage: scripts/ci/test-under-load.sh [--load K] [--soak-runs M] [--suite-runs N] [build-dir]
#   K busy loops (default: one per core, plus one), the soak test M times (default 5), the
#   whole suite N times (default 3); build-dir default: build. In the Debian unstable chroot:
#   scripts/install/sid-chroot.sh scripts/ci/test-under-load.sh build-sid
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
load=$(($(nproc) + 1))
soak_runs=5
suite_runs=3
while [ $# -gt 0 ]; do
  case "$1" in
  --load) load="$2"; shift 2 ;;
  --soak-runs) soak_runs="$2"; shift 2 ;;
  --suite-runs) suite_runs="$2"; shift 2 ;;
  -*) echo "usage: $0 [--load K] [--soak-runs M] [--suite-runs N] [build-dir]" >&2; exit 2 ;;
  *) break ;;
  esac
done
build="$(cd "${1:-$here/build}" && pwd)"
[ -f "$build/CTestTestfile.cmake" ] || { echo "test-under-load: $build is not a built tree" >&2; exit 1; }

loops=()
stop_load() { [ ${#loops[@]} -eq 0 ] || kill "${loops[@]}" 2>/dev/null || true; }
trap stop_load EXIT
for _ in $(seq 1 "$load"); do
  sh -c 'while :; do :; done' &
  loops+=($!)
done
echo "test-under-load: $load busy loops on $(nproc) cores"

run_ctest() { # run_ctest LOG CTEST-ARGS...
  local log="$1"
  shift
  xvfb-run -a -s "-screen 0 1024x768x24 -noreset" \
    ctest --test-dir "$build" --output-on-failure --parallel "$(nproc)" --timeout 1800 "$@" \
    >"$log" 2>&1
}
failed=0
for run in $(seq 1 "$soak_runs"); do
  log="$build/under-load-soak-$run.log"
  started=$(date +%s)
  if run_ctest "$log" -R MapperSoak -V; then result=passed; else result=FAILED; failed=1; fi
  echo "test-under-load: soak $run: $result in $(($(date +%s) - started)) s:" \
    "$(grep -oE 'C\+\+ heap in use [^,]*, malloc in use [^,]*\(bound [0-9]+\)' "$log" | head -n 1);" \
    "$(grep -oE 'resident memory [0-9.]+ -> [0-9.]+ MiB' "$log" | head -n 1) (not asserted)"
done
for run in $(seq 1 "$suite_runs"); do
  log="$build/under-load-suite-$run.log"
  started=$(date +%s)
  if run_ctest "$log"; then result=passed; else result=FAILED; failed=1; fi
  echo "test-under-load: suite $run: $result in $(($(date +%s) - started)) s:" \
    "$(grep -E 'tests passed' "$log" | tail -n 1)"
  grep -E '^\s+[0-9]+ - ' "$log" | sed 's/^/  failed: /' || true
done
exit "$failed"
