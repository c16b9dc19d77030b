#!/usr/bin/env bash
# Test launcher for everything that opens a render window. With a DISPLAY it runs the
# command as is; without one it runs it under a private Xvfb (Mesa llvmpipe). xvfb-run -a
# picks the first free display number racily, so concurrent launches start their search
# at a random number instead of all at :99. -noreset: by default Xvfb resets when its last
# client disconnects, and a window opened during the reset fails to connect.
# MTPT_NO_XVFB=1: run the command as is, for a VTK whose windows need no X server (a VTK
# 9.4 or newer built with OSMesa or EGL, run with VTK_DEFAULT_OPENGL_WINDOW set).
set -euo pipefail
if [ -n "${DISPLAY:-}" ] || [ "${MTPT_NO_XVFB:-0}" = 1 ]; then
  exec "$@"
fi
exec xvfb-run -a -n $((100 + RANDOM % 800)) -s "-screen 0 1024x768x24 -noreset" "$@"
