#!/usr/bin/env bash
# The device kit: one archive, build/device-kit.tar.xz, that measures MTPT on a machine with
# none of its dependencies (the lent GPU machine: no VTK, no X server, nothing to install
# from). Unpacked anywhere, its device-bench.sh runs every measurement
# (Documentation/gpu-and-cores.md).
#
# Usage: scripts/device/device-kit.sh [--smoke-test]
#   Builds MTPT (Release, scripts/install/build-example.sh) and packs the kit. --smoke-test then
#   unpacks it in a bare Debian chroot (debootstrap minbase: no VTK, no X, no Mesa; a newer
#   glibc than the kit's) and runs `device-bench.sh --smoke` there with Mesa's software
#   renderer; its outputs land in build/device-kit-smoke/. Fails when the archive is larger
#   than its budget or any step of the smoke run fails, or when a copy of the kit without
#   zlib (which the chroot has) passes the smoke run's check that every library the kit's
#   programs load is the kit's own.
#
# What the kit holds, under mtpt-device-kit/:
#   libexec/   mtpt_render and the benchmark programs it runs; Xvfb and xkbcomp
#   bin/       one launcher each: the program through the kit's own loader with
#              --library-path lib (glibc included, so nothing of the other machine mixes in)
#   lib/       the shared-library closure of all of them (scripts/device/device-kit-libraries.py),
#              Mesa's GLX library and lib/dri/swrast_dri.so (llvmpipe)
#   share/X11/xkb, data/bluntfin/, device-bench.sh, README.txt, MANIFEST.txt
# Debian's VTK draws in X windows only (GLX), so the GPU is reached through a carried Xvfb
# with glvnd choosing NVIDIA's GLX library (__GLX_VENDOR_LIBRARY_NAME=nvidia), as the
# machine's notes record it working; the Xvfb itself needs Mesa for its own GLX.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="$here/build"
stage="$build/device-kit/mtpt-device-kit"
archive="$build/device-kit.tar.xz"
budget_mib=48
smoke=0
case "${1:-}" in
--smoke-test) smoke=1 ;;
"") ;;
*) sed -n '2,15p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 2 ;;
esac
log() { echo "device-kit: $*" >&2; }
started=$(date +%s)

"$here/scripts/install/build-example.sh" >/dev/null
programs=("$build/example/mtpt_render" "$build/Benchmarks/mtpt_bench_frames"
  "$build/Benchmarks/mtpt_bench_threads" "$build/Benchmarks/mtpt_bench_core" /usr/bin/Xvfb
  /usr/bin/xkbcomp)
multiarch=/usr/lib/x86_64-linux-gnu
mesa=("$multiarch/libGLX_mesa.so.0" "$multiarch/dri/swrast_dri.so")
for f in "${programs[@]}" "${mesa[@]}" /usr/share/X11/xkb/rules/evdev; do
  [ -e "$f" ] || { log "missing $f (scripts/install/install-deps.sh installs what the kit needs)"; exit 1; }
done

rm -rf "$build/device-kit"
mkdir -p "$stage"/{bin,libexec,lib/dri,share/X11,data/bluntfin}
python3 "$here/scripts/device/device-kit-libraries.py" --into "$stage/lib" \
  --stub libz3.so.4 --stub libxml2.so.2 "${programs[@]}" "${mesa[@]}"
cp "$multiarch/libGLX_mesa.so.0" "$stage/lib/"
cp "$multiarch/dri/swrast_dri.so" "$stage/lib/dri/"
cp -rL /usr/share/X11/xkb "$stage/share/X11/xkb"
cp "$here/Data/bluntfin_tets.vtu" "$stage/data/bluntfin/"
cp "$here/scripts/device/device-bench.sh" "$stage/device-bench.sh"

for program in "${programs[@]}"; do
  name="$(basename "$program")"
  cp "$program" "$stage/libexec/$name"
  cat >"$stage/bin/$name" <<EOF
#!/bin/sh
# MTPT device kit: libexec/$name through the kit's loader and libraries only, and then
# the folders in MTPT_KIT_HOST_LIBRARIES (the other machine's GPU driver).
kit="\$(cd "\$(dirname "\$0")/.." && pwd)"
exec "\$kit/lib/ld-linux-x86-64.so.2" \\
  --library-path "\$kit/lib\${MTPT_KIT_HOST_LIBRARIES:+:\$MTPT_KIT_HOST_LIBRARIES}" \\
  --argv0 "\$0" "\$kit/libexec/$name" "\$@"
EOF
  chmod +x "$stage/bin/$name"
done

# Xvfb runs "<XKB_BIN_DIRECTORY>/xkbcomp" to compile its keymap, and has no option for that
# folder (Debian's: /usr/bin). The kit's copy gets an empty one, so that the shell finds
# xkbcomp on PATH, which device-bench.sh points at bin/.
python3 - "$stage/libexec/Xvfb" <<'EOF'
import sys
path = sys.argv[1]
data = open(path, "rb").read()
old = b"\0/usr/bin\0"
if data.count(old) != 1:
    sys.exit(f"device-kit: expected one '/usr/bin' string in {path}, found {data.count(old)}")
open(path, "wb").write(data.replace(old, b"\0\0usr/bin\0"))
EOF

{
  echo "MTPT device kit, made $(date -u '+%Y-%m-%d %H:%M UTC')"
  echo "commit: $(git -C "$here" describe --always --dirty 2>/dev/null || echo unknown)"
  echo "built on: $(. /etc/os-release && echo "$PRETTY_NAME"), $(uname -m)"
  for p in libvtk9.1 libgl1-mesa-dri xvfb libglvnd0 libhwy1 libc6; do
    dpkg-query -W -f='${Package} ${Version}\n' "$p" 2>/dev/null || true
  done
} >"$stage/MANIFEST.txt"
cat >"$stage/README.txt" <<'EOF'
MTPT device kit: MTPT's programs with every library they load (Debian's VTK 9.1, glibc,
Mesa), a private X server and the blunt fin, for a machine that has none of them.

  ./device-bench.sh OUTDIR          everything, in at most 8 minutes: OpenGL's strings,
                                    whole frames against VTK's PT, thread scaling
  ./device-bench.sh --smoke OUTDIR  every step at small sizes, any OpenGL

bin/ holds a launcher per program (bin/mtpt_render --help, bin/mtpt_bench_frames --help,
...); they need a display: device-bench.sh starts the kit's Xvfb. MANIFEST.txt names the
build. The project's Documentation/gpu-and-cores.md explains the figures.
EOF

# Most of the kit is x86 machine code (LLVM alone is half of it): xz's x86 filter and its
# strongest preset keep it under budget. xz compresses one block per thread: blocks of the
# archive's size over the cores, but never under the preset's 64 MiB dictionary, keep every
# core busy (on 2 cores: 115 s instead of 199, for 0.8% more bytes).
log "packing $archive"
block=$((($(du -sb "$stage" | cut -f1) + $(nproc) - 1) / $(nproc)))
[ "$block" -lt $((64 << 20)) ] && block=$((64 << 20))
tar -C "$build/device-kit" -cf - mtpt-device-kit |
  xz -T0 --x86 --lzma2=preset=9e --block-size="$block" >"$archive.part"
mv "$archive.part" "$archive"
bytes=$(stat -c %s "$archive")
mib=$(awk -v b="$bytes" 'BEGIN { printf "%.1f", b / 1048576 }')
log "$archive: $mib MiB ($(du -sh "$stage" | cut -f1) unpacked), in $(($(date +%s) - started)) s"
if [ "$bytes" -gt $((budget_mib * 1048576)) ]; then
  log "the kit is larger than its budget of $budget_mib MiB"
  exit 1
fi
[ "$smoke" = 1 ] || exit 0

# The smoke test: a bare chroot, the kit unpacked at a path with a space in it, and
# device-bench.sh --smoke inside with nothing but the chroot's minbase.
chroot_root="${MTPT_BARE_CHROOT:-/var/cache/mtpt/bare-chroot}"
chroot_suite=trixie
chroot_packages=()
chroot_binds=()
chroot_env=(OMP_NUM_THREADS)
chroot_name=device-kit
# shellcheck source=scripts/install/debian-chroot.sh
. "$here/scripts/install/debian-chroot.sh"
chroot_prepare
work="$(mktemp -d "$chroot_root/tmp/device-kit.XXXXXX")"
trap 'rm -rf "$work"' EXIT
inside="${work#"$chroot_root"}"
mkdir -p "$work/unpacked here"
tar -C "$work/unpacked here" -xJf "$archive"
for forbidden in libvtk9.1 xserver-common libgl1-mesa-dri libgl1; do
  if chroot_run "$chroot_root" dpkg-query -W "$forbidden" >/dev/null 2>&1 9>&-; then
    log "the bare chroot has $forbidden installed: not a bare machine"
    exit 1
  fi
done
log "smoke run in the bare $chroot_suite chroot $chroot_root"
status=0
chroot_run "$chroot_root" "$inside/unpacked here/mtpt-device-kit/device-bench.sh" --smoke \
  "$inside/out" 9>&- || status=$?
rm -rf "$build/device-kit-smoke"
cp -r "$work/out" "$build/device-kit-smoke"
# The library check must see a library the kit lacks, even one the chroot has (zlib, which
# dpkg needs): a kit without it must fail the check.
broken="$work/kit without zlib"
cp -r "$work/unpacked here/mtpt-device-kit" "$broken"
rm "$broken/lib/libz.so.1"
if ! chroot_run "$chroot_root" test -e /usr/lib/x86_64-linux-gnu/libz.so.1 9>&-; then
  log "FAILED: the bare chroot has no zlib: the check of a kit without it shows nothing"
  status=1
elif chroot_run "$chroot_root" "${broken#"$chroot_root"}/device-bench.sh" --check-libraries 9>&-; then
  log "FAILED: a kit without libz.so.1 passed the library check in a chroot that has it"
  status=1
else
  log "a kit without libz.so.1 fails the library check, as it must"
fi
log "smoke run $( [ $status = 0 ] && echo passed || echo "FAILED ($status)"); outputs in" \
  "$build/device-kit-smoke; $(($(date +%s) - started)) s in all"
exit $status
