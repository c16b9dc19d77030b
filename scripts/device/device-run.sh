#!/usr/bin/env bash
# On the lent GPU machine: unpacks the device kit (build/device-kit.tar.xz, made here by
# scripts/device/device-kit.sh and carried with the call) into a fresh folder and runs its
# device-bench.sh into OUTDIR. tar's xz, or Python's tarfile where the machine has no xz.
# Usage: bash scripts/device/device-run.sh OUTDIR [--smoke]
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
out="${1:?usage: device-run.sh OUTDIR [--smoke]}"
archive="$here/build/device-kit.tar.xz"
[ -f "$archive" ] || { echo "device-run: no $archive (scripts/device/device-kit.sh makes it)" >&2; exit 1; }
dest="$(mktemp -d)"
started=$(date +%s)
if ! tar -xJf "$archive" -C "$dest" 2>/dev/null; then
  python3 -c 'import sys, tarfile
kit = tarfile.open(sys.argv[1])
kit.extractall(sys.argv[2], **({"filter": "tar"} if hasattr(tarfile, "tar_filter") else {}))' \
    "$archive" "$dest"
fi
echo "device-run: unpacked in $(($(date +%s) - started)) s into $dest"
exec "$dest/mtpt-device-kit/device-bench.sh" ${2:+"$2"} "$out"
