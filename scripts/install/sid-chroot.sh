#!/usr/bin/env bash
# Today's stack in a Debian unstable (sid) chroot: VTK 9.6, ParaView 6.1, PyVista, Python
# 3.14 and Mesa, from Debian's archive, beside the bookworm host and without touching it.
#
# Usage: scripts/install/sid-chroot.sh [COMMAND [ARGS...]]
#   Makes the chroot, or reuses the one cached on this machine, then runs COMMAND inside it
#   (default: print the versions) in this checkout, which is bind-mounted at the same path.
#   The exit status is COMMAND's.
#
# The chroot lives in MTPT_SID_CHROOT (default /var/cache/mtpt/sid-chroot), outside any
# checkout, so every clone and every CI run on the machine shares it. How it is made, kept
# up to date with the archive and entered: scripts/debian-chroot.sh.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
chroot_root="${MTPT_SID_CHROOT:-/var/cache/mtpt/sid-chroot}"
chroot_suite=sid

# Everything the build, the tests, the Python package and the plugin need inside.
chroot_packages=(
  build-essential cmake ninja-build pkg-config dpkg-dev # toolchain
  libgtest-dev googletest                               # unit tests
  libvtk9-dev python3-vtk9                              # VTK 9.6 and its Python
  paraview paraview-dev python3-paraview openmpi-bin    # ParaView 6.1, pvpython, MPI pvbatch
  python3-pyvista                                       # PyVista
  python3-dev python3-venv python3-pip python3-pytest   # pip from source, pytest
  xvfb xauth x11-apps                                   # headless OpenGL (Mesa llvmpipe); xwd
  libhwy-dev libcli11-dev                               # SIMD dispatch, argument parsing
  ca-certificates
)

chroot_binds=("$here")   # the checkout, at the same path
chroot_workdir="$here"
chroot_env=(MTPT_IN_SID_CHROOT)
chroot_name=sid-chroot
export MTPT_IN_SID_CHROOT=1
# shellcheck source=scripts/install/debian-chroot.sh
. "$here/scripts/install/debian-chroot.sh"
chroot_prepare

if [ $# -eq 0 ]; then
  set -- sh -c 'for p in libvtk9-dev paraview python3-pyvista python3 libgl1-mesa-dri; do
    dpkg-query -W -f="\${Package} \${Version}\n" "$p"; done'
fi
# The command does not inherit the lock: this script holds it until the command ends, and a
# daemon the command leaves behind (an X server, say) must not keep it.
chroot_run "$chroot_root" "$@" 9>&-
