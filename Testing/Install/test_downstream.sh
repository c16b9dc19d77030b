#!/usr/bin/env bash
# A downstream project finds the installed package: install this build to a temporary
# prefix, build Examples/ against it with find_package(MTPT), render the default data set,
# and check that the image shows something. Then a frame the mapper reports an error for
# (the CPU backend's read-back made to fail, MTPT_TESTING_FAULT) must end mtpt_render with
# exit status 1, the mapper's message and what to change, and no image.
# Usage: test_downstream.sh <source-dir> <build-dir>
set -euo pipefail
source_dir="$1"
build_dir="$2"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cmake --install "$build_dir" --prefix "$work/prefix" >/dev/null
# The VTK the build used (Debian's, or another one given with VTK_DIR).
vtk_dir="$(sed -n 's/^VTK_DIR:[A-Z]*=//p' "$build_dir/CMakeCache.txt")"
cmake -S "$source_dir/Examples" -B "$work/example" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$work/prefix" ${vtk_dir:+-DVTK_DIR="$vtk_dir"} >/dev/null
cmake --build "$work/example" >/dev/null
"$source_dir/Testing/xvfb-launch.sh" "$work/example/mtpt_render" --size 160x120 --frames 1 \
  --background white --output "$work/out.png"
/usr/bin/python3 - "$work/out.png" <<'PY'
import sys
from vtkmodules.vtkIOImage import vtkPNGReader
reader = vtkPNGReader()
reader.SetFileName(sys.argv[1])
reader.Update()
pixels = reader.GetOutput().GetPointData().GetScalars()
n = pixels.GetNumberOfTuples()
c = pixels.GetNumberOfComponents()
drawn = sum(1 for i in range(n) if any(pixels.GetValue(i * c + k) < 250 for k in range(3)))
print("downstream render: %d of %d pixels drawn" % (drawn, n))
sys.exit(0 if drawn > 0.01 * n else 1)
PY
status=0
MTPT_TESTING_FAULT=cpu-read-back "$source_dir/Testing/xvfb-launch.sh" \
  "$work/example/mtpt_render" --size 160x120 --frames 1 --backend cpu \
  --output "$work/failed.png" >"$work/failed.log" 2>&1 || status=$?
cat "$work/failed.log"
[ "$status" = 1 ] || { echo "downstream render: a failed frame exited with $status, not 1"; exit 1; }
[ ! -e "$work/failed.png" ] || { echo "downstream render: a failed frame wrote its image"; exit 1; }
grep -q "reading the window's colour and depth back failed" "$work/failed.log" &&
  grep -q "mtpt_render: the mapper (.*) reported an error for a frame" "$work/failed.log" ||
  { echo "downstream render: the failed frame's messages are missing"; exit 1; }
echo "downstream render: a failed frame exits with 1 and writes nothing"
