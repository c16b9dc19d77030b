#!/usr/bin/env bash
# Builds the ParaView plugin MTPT (Plugin/) in its own build tree and tests it headless:
#   1. pvpython and 2. pvbatch load the plugin, show the blunt-fin mesh as the representation
#      "Multi-threaded projected tetra" and compare the image with ParaView's own
#      "Projected tetra" of the same view, then change each mapper setting by its property;
#   3. pvpython: a translucent sphere in front of, behind and inside the mesh, the view
#      depth-peeling volumes: the picture against the composite of its layers, both backends;
#   4. pvbatch on 2 MPI ranks: the mesh redistributed over the ranks (each must hold cells),
#      drawn by the mapper on each and blended by ParaView's ordered compositing, compared
#      with the same script's image from 1 rank;
#   5. pvpython, pvbatch and pvbatch on 2 MPI ranks: the mesh cut into two halves, each its
#      own representation in one view: drawn together, the whole mesh's picture; with
#      Composite With Other Volumes off, one after the other, visibly not;
#   6. client-server: pvpython connected to a 2-rank pvserver, the plugin loaded on both
#      sides, compared with the same 1-rank image.
# Prints the figures (RMSE in [0,1] RGB) and exits non-zero on any failure.
#
# Usage: scripts/plugin.sh [build-dir]   (default: build-plugin)
# Needs the packages of scripts/install/install-deps.sh (paraview, paraview-dev, openmpi-bin, xvfb).
# MTPT_UPDATE_SCREENSHOT=1 also copies the pvpython image to Documentation/paraview_plugin.png
# and the depth-peeling test's sphere inside the mesh to Documentation/paraview_peeling.png.
#
# python3-paraview (pvpython, and the paraview Python package that pvbatch runs) conflicts
# with python3-vtk9, which Debian's VTK 9.1 (libvtk9-dev, the main build) needs, and
# paraview-dev's CMake package names its files (Documentation/environment.md). Unless it is
# installed, its .deb is downloaded (not installed) into the build tree and extracted there;
# the plugin's CMake reads ParaView's wrapping hierarchy files from it, and pvpython/pvbatch
# run with that copy first on their Python path. Nothing is installed or changed under /usr.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="$(mkdir -p "${1:-$here/build-plugin}" && cd "${1:-$here/build-plugin}" && pwd)"
arch="$(dpkg-architecture -qDEB_HOST_MULTIARCH 2>/dev/null || echo x86_64-linux-gnu)"
jobs="$(nproc)"

data="$here/Data/bluntfin_tets.vtu"
[ -f "$data" ] || { echo "plugin.sh: bluntfin_tets.vtu not found" >&2; exit 1; }

installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }
for p in paraview paraview-dev openmpi-bin xvfb; do
  if ! installed "$p"; then
    echo "plugin.sh: package $p is missing; run scripts/install/install-deps.sh" >&2
    exit 1
  fi
done

# --- ParaView's Python: installed, or python3-paraview's .deb extracted into the build tree.
package_root=""
pvpython=/usr/bin/pvpython
pvbatch=/usr/bin/pvbatch
if ! installed python3-paraview; then
  package_root="$build/python3-paraview"
  version="$(dpkg-query -W -f='${Version}' paraview)"  # python3-paraview must match it
  if [ "$(cat "$package_root/.version" 2>/dev/null || true)" != "$version" ]; then
    mkdir -p "$build/debs"
    find_deb() { find "$build/debs" -maxdepth 1 -name "python3-paraview_${version}_*.deb"; }
    if [ -z "$(find_deb)" ]; then
      echo "plugin.sh: downloading python3-paraview $version (not installed)"
      # Package lists may be missing on a machine whose packages were all present (then
      # install-deps.sh never ran apt-get update): update once and try again.
      (cd "$build/debs" && { timeout 600 apt-get download -q "python3-paraview=$version" ||
        { timeout 600 apt-get update -qq &&
          timeout 600 apt-get download -q "python3-paraview=$version"; }; })
    fi
    rm -rf "$package_root"
    dpkg-deb -x "$(find_deb | head -n 1)" "$package_root"
    echo "$version" >"$package_root/.version"
  fi
  # At start-up VTK's and ParaView's Python setup put first on sys.path, ahead of
  # PYTHONPATH, the lib/python3/dist-packages found above the executable and above
  # libvtkCommonCore; under /usr that folder holds Debian's VTK 9.1 Python package
  # (python3-vtk9), and ParaView crashes importing it. Run through links inside the extracted
  # tree (pvbatch; libvtkCommonCore found there first via LD_LIBRARY_PATH), both find the
  # extracted folder instead.
  mkdir -p "$package_root/usr/lib/$arch"
  for core in /usr/lib/"$arch"/libvtkCommonCore-pv*.so.1; do
    [ -e "$core" ] && ln -sf "$core" "$package_root/usr/lib/$arch/"
  done
  ln -sf "$(readlink -f /usr/bin/pvbatch)" "$package_root/usr/bin/pvbatch"
  pvpython="$package_root/usr/bin/pvpython"
  pvbatch="$package_root/usr/bin/pvbatch"
  export LD_LIBRARY_PATH="$package_root/usr/lib/$arch${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
  export PYTHONPATH="$package_root/usr/lib/python3/dist-packages${PYTHONPATH:+:$PYTHONPATH}"
fi

# --- Configure and build (Debian's python3: another one on PATH cannot load ParaView's).
timeout 600 cmake -S "$here/Plugin" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DPython3_EXECUTABLE=/usr/bin/python3 -DMTPT_PARAVIEW_PACKAGE_ROOT="$package_root"
timeout 1800 cmake --build "$build" --parallel "$jobs"
plugin="$(find "$build/lib" -name MTPT.so -path '*/plugins/MTPT/*' | head -n 1)"
[ -n "$plugin" ] || { echo "plugin.sh: MTPT.so was not built" >&2; exit 1; }

# --- Tests. Every step that could hang runs under timeout. One X server per step, with
# -noreset: without it Xvfb resets between clients, an MPI rank's OpenGL probe fails,
# ParaView turns remote rendering off and hangs in its ordered-compositing redistribution.
out="$build/Testing/plugin"
mkdir -p "$out"
rm -f "$out"/*.png "$out"/*.log
tests="$here/Plugin/Testing"
export PYTHONDONTWRITEBYTECODE=1 # no __pycache__ in the source tree
headless() {
  if [ -z "${DISPLAY:-}" ]; then
    timeout 600 xvfb-run -a -s "-screen 0 1024x768x24 -noreset" "$@"
  else
    timeout 600 "$@"
  fi
}
step() { # step NAME COMMAND...: runs a test, keeps its output in NAME.log, stops on failure
  local name="$1"
  shift
  echo "plugin.sh: $name"
  if ! headless "$@" >"$out/$name.log" 2>&1; then
    grep -E '^(PASS|FAIL)|Error|error|Traceback' "$out/$name.log" | head -n 40 >&2 || true
    echo "plugin.sh: $name FAILED (log: $out/$name.log)" >&2
    exit 1
  fi
  grep -E '^(PASS|FAIL)|RMSE|cells per rank|rank\(s\)' "$out/$name.log" | sed 's/^/  /' || true
}

step pvpython "$pvpython" "$tests/test_plugin_render.py" "$plugin" "$data" "$out" pvpython
step pvbatch "$pvbatch" "$tests/test_plugin_render.py" "$plugin" "$data" "$out" pvbatch
step peeling "$pvpython" "$tests/test_plugin_peeling.py" "$plugin" "$data" "$out" peeling
step pvbatch_1rank "$pvbatch" "$tests/test_plugin_parallel.py" "$plugin" "$data" "$out" \
  parallel_1rank
step pvbatch_2ranks timeout 500 mpiexec --allow-run-as-root --oversubscribe -n 2 \
  "$pvbatch" "$tests/test_plugin_parallel.py" "$plugin" "$data" "$out" parallel_2ranks \
  "$out/parallel_1rank.png"
step volumes_pvpython "$pvpython" "$tests/test_plugin_volumes.py" "$plugin" "$data" "$out" \
  volumes_pvpython
step volumes_pvbatch "$pvbatch" "$tests/test_plugin_volumes.py" "$plugin" "$data" "$out" \
  volumes_pvbatch
step volumes_2ranks timeout 500 mpiexec --allow-run-as-root --oversubscribe -n 2 \
  "$pvbatch" "$tests/test_plugin_volumes.py" "$plugin" "$data" "$out" volumes_2ranks
step pvserver_2ranks "$tests/client_server.sh" "$pvpython" "$plugin" "$data" "$out" \
  pvserver_2ranks "$out/parallel_1rank.png"

if [ "${MTPT_UPDATE_SCREENSHOT:-0}" = 1 ]; then
  cp "$out/pvpython_mtpt.png" "$here/Documentation/paraview_plugin.png"
  cp "$out/peeling_inside_cpu_fxaa.png" "$here/Documentation/paraview_peeling.png"
fi

echo "plugin.sh: figures"
grep -h -E 'RMSE [0-9]' "$out"/pvpython.log "$out"/pvbatch.log "$out"/peeling.log \
  "$out"/pvbatch_2ranks.log "$out"/volumes_*.log \
  "$out"/pvserver_2ranks.log \
  | grep -v -E '^(PASS|FAIL)' | sed 's/^/  /' || true
echo "plugin.sh: all plugin tests passed (images in $out)"
