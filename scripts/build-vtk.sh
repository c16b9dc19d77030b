#!/usr/bin/env bash
# Builds a minimal current VTK (9.4 or newer) from a source tree, headless: no X, no EGL, its
# render windows made through OSMesa, which VTK loads at run time (dlopen of
# libOSMesa.so.8, from Debian's libosmesa6). MTPT is then built and tested against it with
# scripts/test-vtk.sh. Nothing is downloaded: the source tree is given (a release of
# https://gitlab.kitware.com/vtk/vtk, e.g. a `git archive v9.6.2` of it).
#
# Usage: scripts/build-vtk.sh SOURCE-DIR PREFIX [--python] [--jobs N]
#   SOURCE-DIR  VTK's source tree (its top-level CMakeLists.txt)
#   PREFIX      where VTK is installed; its build tree is PREFIX-build
#   --python    also wrap VTK (and so MTPT) for Python (needs python3-dev; slower)
#
# The modules are those MTPT's module, tests, benchmarks and example use (and what they
# depend on); every other module and group is off. About 2,100 translation units without
# Python: one to two hours on 2 cores. Re-running resumes the build.
set -euo pipefail

usage() {
  echo "usage: $0 SOURCE-DIR PREFIX [--python] [--jobs N]" >&2
  exit 2
}
[ $# -ge 2 ] || usage
source_dir="$(cd "$1" && pwd)"
prefix="$2"
shift 2
python=OFF
jobs="$(nproc)"
while [ $# -gt 0 ]; do
  case "$1" in
    --python) python=ON ;;
    --jobs) jobs="${2:?--jobs needs a number}"; shift ;;
    *) usage ;;
  esac
  shift
done
[ -f "$source_dir/CMakeLists.txt" ] && [ -d "$source_dir/Rendering/OpenGL2" ] ||
  { echo "build-vtk: $source_dir is not a VTK source tree" >&2; exit 1; }
version="$(sed -n 's/^set(VTK_\(MAJOR\|MINOR\|BUILD\)_VERSION \([0-9]*\)).*/\2/p' \
  "$source_dir/CMake/vtkVersion.cmake" | paste -sd.)"
echo "build-vtk: VTK $version from $source_dir into $prefix (Python wrapping $python)"

here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$here/scripts/install-deps.sh"
# OSMesa, the library VTK's headless window loads at run time.
if ! dpkg-query -W -f='${Status}' libosmesa6 2>/dev/null | grep -q "install ok installed"; then
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libosmesa6
fi
if [ "$python" = ON ] &&
  ! dpkg-query -W -f='${Status}' python3-dev 2>/dev/null | grep -q "install ok installed"; then
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-dev
fi

modules=(
  CommonCore CommonDataModel CommonExecutionModel CommonMath
  FiltersCore FiltersGeneral FiltersSources ImagingCore
  IOImage IOLegacy IOXML
  RenderingCore RenderingOpenGL2 RenderingVolume RenderingVolumeOpenGL2 RenderingUI
  InteractionStyle
  ChartsCore ViewsContext2D RenderingContextOpenGL2   # the benchmarks' plots
)
module_args=()
for m in "${modules[@]}"; do
  module_args+=("-DVTK_MODULE_ENABLE_VTK_$m=YES")
done
if [ "$python" = ON ]; then
  module_args+=("-DVTK_MODULE_ENABLE_VTK_WrappingPythonCore=YES")
fi

build="${prefix%/}-build"
started=$(date +%s)
cmake -S "$source_dir" -B "$build" -G Ninja \
  -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_INSTALL_PREFIX="$prefix" \
  -DBUILD_SHARED_LIBS=ON \
  -DVTK_BUILD_TESTING=OFF \
  -DVTK_BUILD_EXAMPLES=OFF \
  -DVTK_BUILD_DOCUMENTATION=OFF \
  -DVTK_ENABLE_REMOTE_MODULES=OFF \
  -DVTK_BUILD_ALL_MODULES=OFF \
  -DVTK_GROUP_ENABLE_StandAlone=DONT_WANT \
  -DVTK_GROUP_ENABLE_Rendering=DONT_WANT \
  -DVTK_GROUP_ENABLE_Imaging=DONT_WANT \
  -DVTK_GROUP_ENABLE_MPI=DONT_WANT \
  -DVTK_GROUP_ENABLE_Qt=DONT_WANT \
  -DVTK_GROUP_ENABLE_Views=DONT_WANT \
  -DVTK_GROUP_ENABLE_Web=DONT_WANT \
  -DVTK_USE_MPI=OFF \
  -DVTK_WRAP_PYTHON="$python" \
  -DVTK_USE_X=OFF \
  -DVTK_OPENGL_HAS_EGL=OFF \
  -DVTK_USE_WAYLAND_OPENGL=OFF \
  "${module_args[@]}"
cmake --build "$build" --parallel "$jobs"
cmake --install "$build" >/dev/null
echo "build-vtk: VTK $version installed in $prefix after $(($(date +%s) - started)) s" \
  "($(find "$build" -name '*.o' | wc -l) object files)"
