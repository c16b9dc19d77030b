#!/usr/bin/env bash
# The picture of ParaView 6.1's window with the plugin (Documentation/paraview.md): in the
# Debian unstable chroot, ParaView's GUI on a private Xvfb runs scripts/figures/paraview_gui_scene.py
# (the plugin loaded, the blunt fin shown as "Multi-threaded projected tetra"), and xwd
# takes the screen once the scene is up.
#
# Usage: scripts/figures/paraview-gui-figure.sh [output.png]   (default Documentation/paraview_6.1_gui.png)
# Needs the plugin built in build-sid-plugin (scripts/ci/test-sid.sh builds it).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
output="$(realpath -m "${1:-$here/Documentation/paraview_6.1_gui.png}")"
plugin="$(find "$here/build-sid-plugin/lib" -name MTPT.so -path '*/plugins/MTPT/*' 2>/dev/null | head -n 1)"
[ -n "$plugin" ] || { echo "paraview-gui-figure: no plugin in build-sid-plugin (run scripts/ci/test-sid.sh)" >&2; exit 1; }
case "$output" in "$here"/*) ;; *) echo "paraview-gui-figure: write inside the checkout" >&2; exit 1 ;; esac
work="$here/build-sid-plugin/gui-figure"
# A home of its own; --dr (no user settings) also leaves out the welcome dialog.
rm -rf "$work" && mkdir -p "$work/home"
"$here/scripts/install/sid-chroot.sh" bash -c '
  set -euo pipefail
  work="$1"; plugin="$2"; data="$3"; scene="$4"; output="$5"
  command -v xwd >/dev/null || { echo "paraview-gui-figure: xwd missing in the chroot" >&2; exit 1; }
  Xvfb :57 -screen 0 1360x860x24 -nolisten tcp >"$work/xvfb.log" 2>&1 &
  xvfb=$!
  trap "kill \$xvfb 2>/dev/null || true" EXIT
  sleep 2
  HOME="$work/home" DISPLAY=:57 MTPT_PLUGIN="$plugin" MTPT_DATA="$data" MTPT_READY="$work/ready" \
    paraview --dr -geometry 1360x860+0+0 --script="$scene" >"$work/paraview.log" 2>&1 &
  gui=$!
  for _ in $(seq 1 120); do [ -f "$work/ready" ] && break; sleep 1; done
  [ -f "$work/ready" ] || { tail -n 30 "$work/paraview.log" >&2; kill $gui; exit 1; }
  sleep 8 # the first render and the panels
  DISPLAY=:57 xwd -root -silent >"$work/screen.xwd"
  kill $gui 2>/dev/null || true
  python3 - "$work/screen.xwd" "$output" <<PY
import struct, sys
import numpy as np
from PIL import Image
data = open(sys.argv[1], "rb").read()
header = struct.unpack(">25I", data[:100])
size, width, height, order, bpp, bpl, ncolors = (header[i] for i in (0, 4, 5, 7, 11, 12, 19))
stride = bpl // width  # a 24-bit Xvfb screen: 4 bytes a pixel, whatever bits_per_pixel says
assert stride == 4, (bpp, bpl, width)
pixels = data[size + 12 * ncolors:]
rows = np.frombuffer(pixels[:bpl * height], np.uint8).reshape(height, bpl)[:, :width * 4]
quads = rows.reshape(height, width, 4)  # B G R X (LSB first) or X R G B (MSB first)
rgb = quads[:, :, 2::-1] if order == 0 else quads[:, :, 1:]
Image.fromarray(rgb.copy()).save(sys.argv[2])
print("paraview-gui-figure:", sys.argv[2], width, "x", height)
PY
' bash "$work" "$plugin" "$here/Data/bluntfin_tets.vtu" "$here/scripts/figures/paraview_gui_scene.py" "$output"
