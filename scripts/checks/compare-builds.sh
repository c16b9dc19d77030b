#!/usr/bin/env bash
# Shows that a change leaves every image as it was: renders the same images with two
# checkouts of MTPT and compares them pixel for pixel (the PNG files byte for byte: both
# builds write them with the same VTK writer, so equal pixels give equal files).
#
# Usage: scripts/checks/compare-builds.sh BEFORE-BUILD AFTER-BUILD OUT-DIR [MESH-DIR]
#   Each build folder holds a Release build of its checkout and the example built against
#   its install, as scripts/install/build-example.sh makes them (BUILD/Testing/Rendering/
#   mtpt_rendering_tests and BUILD/example/mtpt_render). The images:
#   - every PNG the rendering tests write (mtpt_rendering_tests, run whole in OUT-DIR/<side>/
#     tests, so each test's images land there);
#   - mtpt_render's images of the embedded data set (Data/bluntfin_tets.vtu) and of each
#     mesh under MESH-DIR (default ../shared/data beside this checkout; *.vtu and *.vtk),
#     at 1 and 2 threads, with each backend and both shadings.
# Prints one line per image that differs and a summary; exit status 1 when any differs or
# one side wrote an image the other did not. A side already rendered into OUT-DIR by the same
# build (OUT-DIR/before/complete names it) is not rendered again.
set -euo pipefail
usage="usage: $0 BEFORE-BUILD AFTER-BUILD OUT-DIR [MESH-DIR]"
before="$(cd "${1:?$usage}" && pwd)"
after="$(cd "${2:?$usage}" && pwd)"
out="${3:?$usage}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
meshes="${4:-$here/../shared/data}"
mkdir -p "$out"
out="$(cd "$out" && pwd)"

inputs=("$here/Data/bluntfin_tets.vtu")
if [ -d "$meshes" ]; then
  while IFS= read -r mesh; do inputs+=("$mesh"); done \
    < <(find "$meshes" -name '*.vtu' -o -name '*.vtk' | sort)
fi

render_side() { # render_side BUILD NAME
  local build="$1" side="$out/$2"
  if [ "$(cat "$side/complete" 2>/dev/null)" = "$build" ]; then
    echo "compare-builds: $2's images of $build are there already"
    return
  fi
  rm -rf "$side"
  mkdir -p "$side/tests" "$side/render"
  (cd "$side/tests" &&
    "$here/Testing/xvfb-launch.sh" "$build/Testing/Rendering/mtpt_rendering_tests" \
      >"$side/tests.log" 2>&1) || echo "compare-builds: $2's rendering tests failed (see $side/tests.log)"
  local input name threads backend shading
  for input in "${inputs[@]}"; do
    name="$(basename "${input%.*}")"
    for threads in 1 2; do
      for backend in cpu gl; do
        for shading in vtk pre-integrated; do
          "$here/Testing/xvfb-launch.sh" "$build/example/mtpt_render" "$input" \
            --frames 1 --threads "$threads" --backend "$backend" --shading "$shading" \
            --azimuth 35 --elevation 25 --size 400x300 \
            --output "$side/render/$name-$threads-$backend-$shading.png" \
            >>"$side/render.log" 2>&1 || echo "compare-builds: mtpt_render failed on $name"
        done
      done
    done
  done
  echo "$build" >"$side/complete"
}

render_side "$before" before
render_side "$after" after

differ=0 same=0
while IFS= read -r image; do
  if [ ! -f "$out/after/$image" ]; then
    echo "only before: $image"; differ=$((differ + 1))
  elif cmp -s "$out/before/$image" "$out/after/$image"; then
    same=$((same + 1))
  else
    echo "differs: $image"; differ=$((differ + 1))
  fi
done < <(cd "$out/before" && find . -name '*.png' | sort)
while IFS= read -r image; do
  [ -f "$out/before/$image" ] || { echo "only after: $image"; differ=$((differ + 1)); }
done < <(cd "$out/after" && find . -name '*.png' | sort)
echo "compare-builds: $same images identical, $differ differing or unmatched"
[ "$differ" -eq 0 ]
