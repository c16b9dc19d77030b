#!/usr/bin/env bash
# pip from source, as a user does it: a fresh virtual environment with the system's site
# packages (where the system's VTK, and PyVista if any, are), `pip install <checkout>`, then
# the Python tests against the installed package, from outside the source and build trees.
# Usage: Testing/Python/pip_install.sh SOURCE-DIR WORK-DIR
set -euo pipefail
source="$(cd "${1:?usage: $0 SOURCE-DIR WORK-DIR}" && pwd)"
work="$(mkdir -p "${2:?usage: $0 SOURCE-DIR WORK-DIR}" && cd "$2" && pwd)"
venv="$work/venv"
rm -rf "$venv"
# Debian's interpreter: the one whose site packages hold the system's VTK. pip fetches the
# build backend from PyPI: skipped (exit 77) where PyPI cannot be reached (pypi-reachable.sh).
/usr/bin/python3 -m venv --system-site-packages "$venv"
"$source/Testing/pypi-reachable.sh" "$venv/bin/python" scikit-build-core || exit $?
started=$(date +%s)
"$venv/bin/python" -m pip install --no-cache-dir "$source"
echo "pip_install: built and installed in $(($(date +%s) - started)) s"
cd "$work"
env -u PYTHONPATH -u MTPT_SOURCE_DIR "$venv/bin/python" -c \
  'import mtpt, os; print("pip_install: mtpt from", os.path.dirname(mtpt.__file__))'
exec env -u PYTHONPATH MTPT_SOURCE_DIR="$source" "$source/Testing/xvfb-launch.sh" \
  "$venv/bin/python" -m pytest -p no:cacheprovider -v -rs "$source/Testing/Python"
