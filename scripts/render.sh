#!/usr/bin/env bash
# The README's render command: installs what is missing, builds and installs MTPT, builds
# the downstream example against the install (find_package(MTPT)), and renders the
# embedded data set (Data/bluntfin_tets.vtu) to build/mtpt_default.png, with VTK's
# vtkProjectedTetrahedraMapper beside it (build/mtpt_default-side-by-side.png). Both are
# timed with the camera turning before every frame, in VTK's default window (multisampled)
# and single-sampled, the ratio taking each in its faster window; MTPT's stages apart from
# the whole frame, and frames of an unchanged view apart from those.
# Arguments go to mtpt_render instead of the defaults (see: scripts/render.sh --help).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="$here/build"

"$here/scripts/install/build-example.sh"

args=(--compare-vtk --azimuth 35 --elevation 25 --zoom 1.3
  --output "$build/mtpt_default.png")
if [ $# -gt 0 ]; then args=("$@"); fi
exec "$here/Testing/xvfb-launch.sh" "$build/example/mtpt_render" "${args[@]}"
