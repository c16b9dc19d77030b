#!/usr/bin/env bash
# The device kit's measurements (scripts/device/device-kit.sh packs this file at the kit's top):
# MTPT on a machine with a GPU and many cores, from the kit alone, in at most 8 minutes.
#
# Usage: device-bench.sh [--smoke] OUTDIR
#        device-bench.sh --check-libraries   (step 0 alone: exit status 1 when it fails)
#   0. Every library the kit's programs and its Mesa load resolves inside the kit's lib/.
#   1. OpenGL's vendor and renderer (machine.txt). Without --smoke the run fails unless
#      they are NVIDIA's: the GPU steps are then skipped and the CPU step still runs.
#   2. Whole frames (frames.csv): MTPT's OpenGL backend, its CPU backend and VTK's PT at
#      512x512, 1024x1024 and 1920x1080 in both kinds of window, the camera turning before
#      every frame, on the wavelet (1.08M tetrahedra, with VTK's GPU ray caster on the
#      same field as image data, for scale), a generated 10M-tetrahedron grid and the
#      blunt fin.
#   3. Thread scaling (threads.csv, threads_<mesh>.png): MTPT's CPU stages and CPU backend
#      at 1, 2, 4, 8 and 16 threads on the wavelet and the 10M grid, parallel efficiency
#      per stage.
#   summary.md gathers the tables, log.txt everything printed. --smoke runs every step at
#   small sizes (a 100k grid for the 10M one, small windows, 1 and 2 threads) with any
#   OpenGL, Mesa's llvmpipe included, and checks that every step wrote its rows.
# Any step that fails makes the exit status 1; the others still run. A step that would
# pass the overall deadline is cut short (timeout) and counts as failed.
set -uo pipefail
kit="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"

# check_libraries: every library the programs of libexec/ and the kit's Mesa (loaded by
# glvnd and the X server at run time) depend on, as the kit's loader resolves it for the
# launchers, is a file of the kit's lib/: a library the kit lacks would otherwise be taken
# from the machine where it has one (a different version) and be missing where it has none.
# Prints each that is not, and returns 1 then.
check_libraries() {
  local object listing line name target bad=0
  for object in "$kit"/libexec/* "$kit/lib/libGLX_mesa.so.0" "$kit/lib/dri/swrast_dri.so"; do
    listing="$("$kit/lib/ld-linux-x86-64.so.2" --library-path "$kit/lib" --list "$object" 2>&1)"
    if ! grep -q ' => ' <<<"$listing"; then # never a pass for a listing that did not run
      echo "device-bench: the kit's loader listed no library of $(basename "$object"): $listing"
      bad=1
      continue
    fi
    while IFS= read -r line; do
      case "$line" in
      *" => "*) ;;
      *) continue ;; # the loader itself and the kernel's vDSO
      esac
      name="${line%% => *}"
      name="${name//[[:space:]]/}"
      target="${line#* => }"
      target="${target% (0x*}"
      case "$target" in
      "$kit/lib/"*) ;;
      *)
        echo "device-bench: $(basename "$object") loads $name from outside the kit: $target"
        bad=1
        ;;
      esac
    done <<<"$listing"
  done
  return $bad
}
if [ "${1:-}" = --check-libraries ]; then
  check_libraries && echo "device-bench: every library resolves inside the kit"
  exit
fi

smoke=0
if [ "${1:-}" = --smoke ]; then
  smoke=1
  shift
fi
if [ $# -ne 1 ]; then
  sed -n '2,23p' "$0" | sed 's/^# \{0,1\}//' >&2
  exit 2
fi
mkdir -p "$1" || exit 1
out="$(cd "$1" && pwd)"
work="$(mktemp -d)"
failures=()
started=$(date +%s)
if [ "$smoke" = 1 ]; then
  deadline=$((started + 900))
  meshes=(wavelet grid:100000 bluntfin)
  sizes=64,96x64
  thread_counts=1,2
  threads_size=96
  repeat=1
  repeat_big=1
else
  deadline=$((started + 470)) # 7 min 50 s: the lent machine's call is 8 minutes
  meshes=(wavelet grid:10000000 bluntfin)
  sizes=512,1024,1920x1080
  thread_counts=1,2,4,8,16
  threads_size=1024
  repeat=5
  repeat_big=3
fi
exec > >(tee -a "$out/log.txt") 2>&1

say() { printf '\n== %s (%d s)\n' "$*" $(($(date +%s) - started)); }
fail() {
  echo "device-bench: FAILED: $*"
  failures+=("$*")
}
# step NAME SECONDS FILE COMMAND...: COMMAND with at most SECONDS, and never past the
# deadline; what it prints is appended to FILE too.
step() {
  local name="$1" limit="$2" file="$3" left status
  shift 3
  left=$((deadline - $(date +%s)))
  [ "$left" -lt "$limit" ] && limit=$left
  if [ "$limit" -le 5 ]; then
    fail "$name: no time left before the deadline"
    return 1
  fi
  say "$name (at most $limit s)"
  timeout --kill-after=10 "$limit" "$@" >"$work/step.txt" 2>&1
  status=$?
  tee -a "$file" <"$work/step.txt"
  [ "$status" = 0 ] && return 0
  [ "$status" = 124 ] && fail "$name: cut short after $limit s" || fail "$name: exit status $status"
  return 1
}

# --- The machine --------------------------------------------------------------------------
{
  echo "device-bench $( [ "$smoke" = 1 ] && echo --smoke ), $(date -u '+%Y-%m-%d %H:%M UTC')"
  cat "$kit/MANIFEST.txt"
  echo "cores: $(nproc) ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //'))"
  grep -q avx512f /proc/cpuinfo && echo "instruction set: AVX-512" ||
    { grep -q avx2 /proc/cpuinfo && echo "instruction set: AVX2 (no AVX-512)" || echo "instruction set: below AVX2"; }
  echo "memory: $(awk '/MemTotal/ { printf "%.0f GiB", $2 / 1048576 }' /proc/meminfo)"
  command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader
} >"$out/machine.txt" 2>&1

# --- 0. The kit's libraries -------------------------------------------------------------------
say "libraries"
check_libraries || fail "libraries outside the kit (above)"

# --- The display: the kit's Xvfb, its GLX on the kit's Mesa ---------------------------------
export PATH="$kit/bin:$PATH" # xkbcomp, for Xvfb's keymap
LIBGL_DRIVERS_PATH="$kit/lib/dri" "$kit/bin/Xvfb" -displayfd 3 -screen 0 2048x1200x24 \
  -nolisten tcp -noreset -xkbdir "$kit/share/X11/xkb" 3>"$work/display" >"$work/xvfb.log" 2>&1 &
xvfb=$!
trap 'kill $xvfb 2>/dev/null; rm -rf "$work"' EXIT
trap 'exit 143' TERM INT
for _ in $(seq 100); do
  [ -s "$work/display" ] && break
  kill -0 $xvfb 2>/dev/null || break
  sleep 0.1
done
if [ ! -s "$work/display" ]; then
  cat "$work/xvfb.log"
  echo "device-bench: FAILED: the kit's Xvfb did not start"
  exit 1
fi
export DISPLAY=":$(head -n1 "$work/display")"
export LIBGL_DRIVERS_PATH="$kit/lib/dri"

# --- 1. OpenGL ---------------------------------------------------------------------------------
# Without --smoke: NVIDIA's GLX library from the machine's driver, found where the loader
# would look for it, and chosen by glvnd over the X server's own (Mesa).
opengl() { "$kit/bin/mtpt_bench_frames" --opengl-info 2>&1; }
gpu=1
if [ "$smoke" = 0 ]; then
  nvidia=""
  # ldconfig may list a 32-bit copy first: only the x86-64 one serves the kit's programs.
  for dir in $(ldconfig -p 2>/dev/null |
    awk '/libGLX_nvidia\.so\.0 \(libc6,x86-64/ { sub(/\/[^\/]*$/, "", $NF); print $NF }') \
    /usr/local/nvidia/lib64 /usr/local/nvidia/lib /usr/lib/x86_64-linux-gnu /usr/lib64; do
    [ -e "$dir/libGLX_nvidia.so.0" ] && { nvidia="$dir"; break; }
  done
  if [ -n "$nvidia" ]; then
    export MTPT_KIT_HOST_LIBRARIES="$nvidia" __GLX_VENDOR_LIBRARY_NAME=nvidia
  fi
  say "OpenGL (NVIDIA's GLX library: ${nvidia:-not found})"
  info="$(opengl)"
  if ! grep -q '^OpenGL vendor: NVIDIA' <<<"$info" && [ -n "$nvidia" ]; then
    echo "$info"
    echo "device-bench: not NVIDIA's OpenGL; again with __NV_PRIME_RENDER_OFFLOAD=1"
    export __NV_PRIME_RENDER_OFFLOAD=1
    info="$(opengl)"
  fi
  echo "$info" | tee -a "$out/machine.txt"
  if ! grep -q '^OpenGL vendor: NVIDIA' <<<"$info"; then
    fail "OpenGL is not the NVIDIA GPU's (above); the GPU steps are skipped"
    gpu=0
    # The CPU step draws with the kit's Mesa (llvmpipe), as --smoke does: not through the
    # NVIDIA settings that just failed.
    unset MTPT_KIT_HOST_LIBRARIES __GLX_VENDOR_LIBRARY_NAME __NV_PRIME_RENDER_OFFLOAD
    echo "device-bench: the CPU step runs on the kit's Mesa:"
    opengl | tee -a "$out/machine.txt"
  fi
else
  say "OpenGL"
  info="$(opengl)"
  echo "$info" | tee -a "$out/machine.txt"
  grep -q '^OpenGL renderer: ' <<<"$info" && ! grep -q '^OpenGL renderer: unknown' <<<"$info" ||
    { fail "no OpenGL context (above)"; gpu=0; }
fi

# --- 2. Whole frames -----------------------------------------------------------------------
# The budgets put the wavelet and the 10M grid, the goals' meshes, first.
frames() { # frames MESH SECONDS REPEAT
  step "frames, $1" "$2" "$work/frames.md" "$kit/bin/mtpt_bench_frames" --meshes "$1" \
    --sizes "$sizes" --contenders mtpt-gl,mtpt-cpu,vtk-pt,gpu-raycast --data "$kit/data" \
    --slow-limit 3 --repeat "$3" --csv "$out/frames.csv"
}
if [ "$gpu" = 1 ]; then
  frames "${meshes[0]}" 130 "$repeat"
  frames "${meshes[1]}" 150 "$repeat_big"
fi

# --- 3. Threads ----------------------------------------------------------------------------
step "threads" 150 "$work/threads.md" "$kit/bin/mtpt_bench_threads" \
  --meshes "${meshes[0]},${meshes[1]}" --size "$threads_size" --thread-counts "$thread_counts" \
  --repeat "$repeat" --out "$out"

if [ "$gpu" = 1 ]; then
  frames "${meshes[2]}" 90 "$repeat"
fi

# --- Summary and checks ----------------------------------------------------------------------
{
  echo "# device-bench$( [ "$smoke" = 1 ] && echo " --smoke")"
  echo
  sed 's/^/    /' "$out/machine.txt"
  for part in frames threads; do
    [ -f "$work/$part.md" ] && { echo; grep -E '^\||^[a-z].*(tetrahedra|/ mtpt|efficiency)' "$work/$part.md"; }
  done
} >"$out/summary.md"
# rows FILE PATTERN COUNT WHAT: FILE has at least COUNT lines matching PATTERN.
rows() {
  local found
  found=$(grep -cE "$2" "$1" 2>/dev/null)
  [ "${found:-0}" -ge "$3" ] || fail "$4: $1 has ${found:-0} rows matching '$2', expected $3 or more"
}
if [ "$gpu" = 1 ]; then
  nsizes=$(tr ',' '\n' <<<"$sizes" | wc -l)
  for contender in mtpt-gl mtpt-cpu vtk-pt; do
    for mesh in "${meshes[@]}"; do
      rows "$out/frames.csv" "^$mesh,.*,$contender,(on|off)," $((2 * nsizes)) "frames of $contender on $mesh"
    done
  done
  rows "$out/frames.csv" "^wavelet,.*,gpu-raycast,(on|off)," $((2 * nsizes)) "VTK's GPU ray caster on the wavelet"
fi
nthreads=$(tr ',' '\n' <<<"$thread_counts" | wc -l)
for mesh in "${meshes[0]}" "${meshes[1]}"; do
  rows "$out/threads.csv" "^$mesh,.*,frame," "$nthreads" "thread scaling on $mesh"
  png="$out/threads_$(tr -c '[:alnum:]\n' _ <<<"$mesh").png"
  [ -s "$png" ] || fail "no plot $png"
done

say "done"
if [ ${#failures[@]} -gt 0 ]; then
  printf 'device-bench: %d step(s) FAILED:\n' ${#failures[@]}
  printf '  %s\n' "${failures[@]}"
  exit 1
fi
echo "device-bench: every step passed; outputs in $out: $(cd "$out" && echo *)"
