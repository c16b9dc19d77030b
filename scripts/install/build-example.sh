#!/usr/bin/env bash
# Builds MTPT (Release) in build/, installs it into build/install and builds the downstream
# example (Examples/, find_package(MTPT)) against that install: build/example/mtpt_render.
# Installs the Debian packages that are missing first. Used by scripts/render.sh and
# scripts/device-kit.sh.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="$here/build"

"$here/scripts/install/install-deps.sh"
cmake -S "$here" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" --parallel "$(nproc)"
cmake --install "$build" --prefix "$build/install" >/dev/null
cmake -S "$here/Examples" -B "$build/example" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$build/install" >/dev/null
cmake --build "$build/example"
