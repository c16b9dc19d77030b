#!/usr/bin/env bash
# Checks that the image tests can see the visibility order: runs the rendering tests with
# the cells drawn in a deliberately wrong order and requires each wrong order to fail at
# least MIN_FAILURES tests (a suite that passes with a wrong order does not test the order).
#   reversed: front to back instead of back to front   (MTPT_TESTING_ORDER=reversed)
#   storage:  the cells as stored, not sorted at all     (MTPT_TESTING_ORDER=storage)
# Prints, for each, how many tests failed and which.
#
# Usage: scripts/ci/mutation-check.sh [build-dir]   (default: build; built by scripts/test.sh)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="${1:-$here/build}"
tests="$build/Testing/Rendering/mtpt_rendering_tests"
min_failures="${MIN_FAILURES:-10}"
[ -x "$tests" ] || { echo "mutation-check: $tests not built (run scripts/test.sh)" >&2; exit 1; }

status=0
for order in reversed storage; do
  log="$build/mutation-$order.log"
  # The test program fails, as it must: its output is what counts.
  MTPT_TESTING_ORDER="$order" timeout 900 "$here/Testing/xvfb-launch.sh" "$tests" \
    --gtest_brief=1 >"$log" 2>&1 || true
  failed="$(grep -E '^\[  FAILED  \] [A-Za-z]' "$log" | sed -E 's/ \([0-9]+ ms\)$//' | sort -u)"
  count="$(printf '%s' "$failed" | grep -c . || true)"
  passed="$(grep -E '^\[  PASSED  \] [0-9]+ tests?' "$log" | grep -oE '[0-9]+' | head -n 1)"
  echo "mutation-check: order '$order': $count tests failed, ${passed:-0} passed"
  printf '%s\n' "$failed" | sed 's/^\[  FAILED  \] /  /'
  if [ "$count" -lt "$min_failures" ]; then
    echo "mutation-check: order '$order' failed fewer than $min_failures tests: the image" \
      "tests do not see the visibility order (log: $log)" >&2
    status=1
  fi
done
exit "$status"
