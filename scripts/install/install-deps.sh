#!/usr/bin/env bash
# Installs every Debian package MTPT needs, idempotently: packages already present are
# skipped, and apt is not touched at all when nothing is missing.
set -euo pipefail

packages=(
  build-essential cmake ninja-build       # toolchain
  libgtest-dev googletest                 # unit tests
  libvtk9-dev                             # VTK 9.1: mapper, loaders for real meshes
  xvfb xauth                              # headless OpenGL (Mesa llvmpipe) for image tests
  paraview paraview-dev openmpi-bin       # ParaView 5.11 plugin (its own VTK 9.2), MPI pvbatch
  clang libomp-dev libclang-rt-14-dev     # ThreadSanitizer with an OpenMP runtime it can see, libFuzzer
  libhwy-dev                              # Google Highway: SIMD compositor, run-time dispatch
  libcli11-dev                            # command-line parsing of the benchmarks and the example
  python3-pytest python3-venv             # Python tests; pip install from source in a venv
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
