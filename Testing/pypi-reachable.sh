#!/usr/bin/env bash
# Whether the tests that install from PyPI can run: exits 0 when PYTHON's pip reaches its
# package index (the one the machine configures) and finds PACKAGE there. Otherwise it says
# so and exits 77, which ctest reports as a skip (SKIP_RETURN_CODE), for machines without
# the network (many HPC sites); with MTPT_REQUIRE_PYPI=1 (CI) it exits 1 instead: there the
# tests must run. A PYTHON without pip fails (exit 1): the test asks the wrong interpreter.
# Usage: Testing/pypi-reachable.sh PYTHON PACKAGE
set -uo pipefail
python="${1:?usage: $0 PYTHON PACKAGE}"
package="${2:?usage: $0 PYTHON PACKAGE}"
# No pip at all is the caller's mistake, not the network's: a failure, never a skip.
if ! "$python" -m pip --version >/dev/null 2>&1; then
  echo "pypi-reachable: $python has no pip: ask a virtual environment's (python3 -m venv)"
  exit 1
fi
if "$python" -m pip index versions --retries 0 --timeout 15 --disable-pip-version-check \
  "$package" >/dev/null 2>&1; then
  exit 0
fi
echo "pypi-reachable: pip cannot reach its package index for $package: this test installs" \
  "from PyPI and is skipped (ctest -LE pypi leaves such tests out)"
if [ "${MTPT_REQUIRE_PYPI:-0}" = 1 ]; then
  echo "pypi-reachable: MTPT_REQUIRE_PYPI=1: failing instead"
  exit 1
fi
exit 77
