#!/usr/bin/env bash
# Runs scripts/checks/check-function-length.py (with its self-test) on Source/ with lizard, a
# pinned version from PyPI in a virtual environment under WORK-DIR, made once and reused;
# skipped (exit 77) when it must be installed and PyPI cannot be reached (pypi-reachable.sh).
# Usage: Testing/function-length.sh PYTHON SOURCE-DIR WORK-DIR
set -euo pipefail
python="${1:?usage: $0 PYTHON SOURCE-DIR WORK-DIR}"
source="$(cd "${2:?usage: $0 PYTHON SOURCE-DIR WORK-DIR}" && pwd)"
venv="${3:?usage: $0 PYTHON SOURCE-DIR WORK-DIR}/lizard-venv"
lizard="lizard==1.24.3"
installed="$("$venv/bin/python" -m pip show "${lizard%%=*}" 2>/dev/null | sed -n 's/^Version: //p')" || true
if [ "$installed" != "${lizard##*=}" ]; then
  "$source/Testing/pypi-reachable.sh" "$python" "${lizard%%=*}" || exit $?
  rm -rf "$venv"
  "$python" -m venv "$venv"
  "$venv/bin/python" -m pip install --quiet --disable-pip-version-check "$lizard"
fi
exec "$venv/bin/python" "$source/scripts/checks/check-function-length.py" --self-test "$source/Source"
