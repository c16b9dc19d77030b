#!/usr/bin/env bash
# The README's render command: installs what is missing, builds and installs MTPT, builds
# the downstream example against the install (find_package(MTPT)), and renders the
# embedded data set (Data/bluntfin_tets.vtu) to build/mtpt_default.png, printing MTPT's
# per-stage times beside VTK's vtkProjectedTetrahedraMapper on the same scene.
# Arguments go to mtpt_render (see: scripts/render.sh --help).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="$here/build"

"$here/scripts/install-deps.sh"
cmake -S "$here" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" --parallel "$(nproc)"
cmake --install "$build" --prefix "$build/install" >/dev/null
cmake -S "$here/Examples" -B "$build/example" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$build/install" >/dev/null
cmake --build "$build/example"

args=(--compare-vtk --output "$build/mtpt_default.png")
if [ $# -gt 0 ]; then args=("$@"); fi
exec "$here/Testing/xvfb-launch.sh" "$build/example/mtpt_render" "${args[@]}"
