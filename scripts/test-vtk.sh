#!/usr/bin/env bash
# Builds MTPT against another VTK than Debian's (a prefix made by scripts/build-vtk.sh, or
# any VTK 9.1 or newer) and runs the whole ctest suite there. A VTK built without X (its
# windows made through OSMesa, as build-vtk.sh makes it) is run with no X server at all:
# VTK_DEFAULT_OPENGL_WINDOW=vtkOSOpenGLRenderWindow, no DISPLAY, no Xvfb.
#
# Usage: scripts/test-vtk.sh VTK-PREFIX [build-dir]   (default build dir: build-vtk-<version>)
# The ParaView plugin and the Python test are left out (ParaView 5.11 has its own VTK; the
# prefix's VTK is not wrapped unless built with --python).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
prefix="$(cd "${1:?usage: $0 VTK-PREFIX [build-dir]}" && pwd)"
vtk_dir="$(dirname "$(find "$prefix" -name vtk-config.cmake -path '*cmake/vtk*' | head -n 1)")"
[ -f "$vtk_dir/vtk-config.cmake" ] || { echo "test-vtk: no VTK CMake package in $prefix" >&2; exit 1; }
version="$(basename "$vtk_dir" | sed 's/^vtk-//')"
build="${2:-$here/build-vtk-$version}"
"$here/scripts/install-deps.sh"

headless=0
if grep -q 'VTK_USE_X:BOOL=OFF' "$prefix-build/CMakeCache.txt" 2>/dev/null ||
  ! grep -rq 'vtkXOpenGLRenderWindow' "$prefix/include" 2>/dev/null; then
  headless=1
fi
echo "test-vtk: VTK $version from $vtk_dir$([ $headless = 1 ] && echo ', headless (OSMesa)')"
started=$(date +%s)
cmake -S "$here" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DVTK_DIR="$vtk_dir"
cmake --build "$build" --parallel "$(nproc)"
env_args=()
if [ "$headless" = 1 ]; then
  env_args=(env -u DISPLAY VTK_DEFAULT_OPENGL_WINDOW=vtkOSOpenGLRenderWindow MTPT_NO_XVFB=1)
fi
"${env_args[@]}" ctest --test-dir "$build" --output-on-failure --parallel "$(nproc)" \
  --timeout 900 -E '^python_mapper$'
echo "test-vtk: VTK $version: build and tests passed in $(($(date +%s) - started)) s"
