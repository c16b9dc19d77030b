#!/usr/bin/env bash
# Runs scripts/checks/check-function-length.py (with its self-test) on Source/ with lizard, a
# pinned version from PyPI in a virtual environment under WORK-DIR, made from PYTHON once and
# reused; skipped (exit 77) when it must be installed and PyPI cannot be reached
# (pypi-reachable.sh). The virtual environment's own pip is asked and installs, as in
# Testing/Python/pip_install.sh: PYTHON may have none (Debian's python3 without python3-pip).
# Usage: Testing/function-length.sh PYTHON SOURCE-DIR WORK-DIR
set -euo pipefail
python="${1:?usage: $0 PYTHON SOURCE-DIR WORK-DIR}"
source="$(cd "${2:?usage: $0 PYTHON SOURCE-DIR WORK-DIR}" && pwd)"
venv="${3:?usage: $0 PYTHON SOURCE-DIR WORK-DIR}/lizard-venv"
lizard="lizard==1.24.3"
installed="$("$venv/bin/python" -m pip show "${lizard%%=*}" 2>/dev/null | sed -n 's/^Version: //p')" || true
if [ "$installed" != "${lizard##*=}" ]; then
  rm -rf "$venv"
  "$python" -m venv "$venv"
  "$source/Testing/pypi-reachable.sh" "$venv/bin/python" "${lizard%%=*}" || exit $?
  "$venv/bin/python" -m pip install --quiet --disable-pip-version-check "$lizard"
fi
exec "$venv/bin/python" "$source/scripts/checks/check-function-length.py" --self-test "$source/Source"
