#!/usr/bin/env bash
# Sanitizer and fuzzing checks of the core library (mtpt_core). Usage:
#   scripts/ci/sanitizers.sh [fuzz-seconds]          (default 60; CI: .ci/run)
#   scripts/ci/sanitizers.sh 3600                    (the long run: an hour of fuzzing)
#
# Two builds of the core and its tests (RelWithDebInfo, Ninja, no VTK module, no benchmarks),
# each in its own build folder; every step runs under `timeout` so CI can never hang:
#   asan  Clang, -fsanitize=address,undefined with libFuzzer's coverage instrumentation
#         (MTPT_BUILD_FUZZERS=ON, which implies MTPT_SANITIZER=address): the core tests.
#         Out-of-bounds and use-after-free accesses, leaks, and undefined behaviour
#         (signed overflow, misaligned or null accesses, bad shifts) abort the test.
#         LLVM's OpenMP runtime runs without hot teams (below), so every leak is ours.
#   fuzz  the same build's libFuzzer target mtpt_fuzz_frame (Testing/Fuzz/FuzzFrame.cxx):
#         random and degenerate meshes and cameras through FramePipeline::Run and the
#         Compositor, every invariant checked, for fuzz-seconds, starting from the checked-in
#         corpus Testing/Fuzz/corpus/FuzzFrame. A failing input is written to
#         <asan build>/artifacts/; reproduce with <asan build>/Testing/Fuzz/mtpt_fuzz_frame
#         <artifact>.
#   tsan  Clang, -fsanitize=thread (MTPT_SANITIZER=thread), OpenMP from LLVM's libomp
#         (-fopenmp=libomp: GCC's libgomp is not instrumented, so TSan would not see its
#         barriers and would report false races) with the Archer OMPT tool, which tells
#         TSan about OpenMP's synchronisation (OMP_TOOL_LIBRARIES=libarcher.so,
#         TSAN_OPTIONS=ignore_noninstrumented_modules=1 as Archer's documentation asks).
#         The core tests run with OMP_NUM_THREADS=4 (more threads than cores, so threads
#         interleave). Data races between OpenMP threads fail the test.
#
# The grid is smaller than the release build's, where the sanitizers cost most:
#   - instruction sets: both builds target x86-64-v2 (-march=x86-64-v2), so Highway compiles
#     the compositor for AVX3, AVX2 and SSE4 (16, 8 and 4 lanes) but not for SSSE3 (4 lanes,
#     as SSE4) and the scalar fallback (which no x86-64 processor of the last 15 years runs);
#     the per-target tests run for those three. The instrumented compositor is most of each
#     build's time and its per-target tests most of the tests' time. The release builds
#     (scripts/test.sh, bookworm and unstable) test every target.
#   - tests: the tests of compiled code only; the checks that are scripts (the layer and
#     function-length checks, the results tables) read the sources and run in scripts/test.sh.
#
# Build folders: build-asan and build-tsan under the repository (ignored by git), or
# MTPT_SANITIZER_BUILD_ROOT/{asan,tsan}, or ASAN_BUILD_DIR, TSAN_BUILD_DIR each (FUZZ_BUILD_DIR:
# the fuzzer's, by default the asan build). MTPT_JOBS: build jobs (default 2).
# MTPT_SANITIZER_PHASES: the phases to run (default "asan fuzz tsan"). MTPT_TSAN_EXCLUDE: a
# ctest -E regex of tests to leave out of the TSan run (default none).
# Every phase runs even if an earlier one failed; the exit status is non-zero if any did.
#
# The long run, `scripts/ci/sanitizers.sh 3600`, fuzzes for an hour (about 400,000
# executions on the 2-core host) after the same asan and tsan phases; it stops at the first failing input
# unless MTPT_FUZZ_FLAGS="-fork=2 -ignore_crashes=1" asks libFuzzer to go on and collect
# every distinct one in the artifacts folder. Its work corpus (<fuzz build>/corpus) is kept
# and resumed by the next run. See Documentation/testing.md, "Sanitizers and fuzzing".
set -uo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
fuzz_seconds="${1:-60}"
if ! [[ "$fuzz_seconds" =~ ^[0-9]+$ ]]; then
  echo "usage: $0 [fuzz-seconds]" >&2
  exit 2
fi
jobs="${MTPT_JOBS:-2}"
phases="${MTPT_SANITIZER_PHASES:-asan fuzz tsan}"
root="${MTPT_SANITIZER_BUILD_ROOT:-}"
asan_dir="${ASAN_BUILD_DIR:-${root:+$root/asan}}"
tsan_dir="${TSAN_BUILD_DIR:-${root:+$root/tsan}}"
asan_dir="${asan_dir:-$here/build-asan}"
tsan_dir="${tsan_dir:-$here/build-tsan}"
fuzz_dir="${FUZZ_BUILD_DIR:-$asan_dir}"

"$here/scripts/install/install-deps.sh" || exit 1

summary=()
failed=0
now() { date +%s; }

# step NAME SECONDS COMMAND...: runs COMMAND under timeout, output to the phase log.
step() {
  local name="$1" limit="$2"
  shift 2
  echo "== $name: $*" >>"$log"
  timeout --kill-after=30 "$limit" "$@" >>"$log" 2>&1
  local rc=$?
  if [ "$rc" -eq 124 ] || [ "$rc" -eq 137 ]; then
    echo "== $name: timed out after $limit s" >>"$log"
  fi
  return "$rc"
}

# finish PHASE STATUS DETAILS: records the phase's one-line summary and prints it.
finish() {
  local line
  line="$(printf 'sanitizers: %-4s %-4s %s' "$1" "$2" "$3")"
  summary+=("$line")
  echo "$line"
  if [ "$2" != PASS ]; then
    failed=1
    echo "sanitizers: $1: last lines of $log:"
    grep -vE '^#[0-9]+[[:space:]]+(NEW|REDUCE|pulse|RELOAD)' "$log" | tail -n 60
  fi
}

# configure DIR CC CXX CMAKE-ARGS...: the core only (no VTK module, no benchmarks), for
# x86-64-v2 (the smaller grid of instruction sets, above).
configure() {
  local dir="$1" cc="$2" cxx="$3"
  shift 3
  step configure 300 env CC="$cc" CXX="$cxx" cmake -S "$here" -B "$dir" -G Ninja \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo -DMTPT_BUILD_VTK_MODULE=OFF \
    -DMTPT_BUILD_BENCHMARKS=OFF -DCMAKE_C_FLAGS=-march=x86-64-v2 \
    -DCMAKE_CXX_FLAGS=-march=x86-64-v2 "$@"
}

# configure_asan DIR: Clang, ASan + UBSan and libFuzzer's instrumentation, the tests and the
# fuzz target.
configure_asan() {
  configure "$1" clang clang++ -DMTPT_BUILD_FUZZERS=ON -DMTPT_SANITIZER=address \
    -DMTPT_BUILD_TESTING=ON
}

# compiled_tests DIR [EXCLUDE]: sets `selected` to ctest's arguments for the core tests of DIR
# that run a program built there, leaving out those that run a script (python3, bash) and
# those that the regex EXCLUDE matches.
compiled_tests() {
  local scripts
  scripts="$(ctest --test-dir "$1" -L core --show-only=json-v1 | python3 -c '
import json, os, sys
build = os.path.realpath(sys.argv[1])
names = [t["name"] for t in json.load(sys.stdin)["tests"]
         if not os.path.realpath(t["command"][0]).startswith(build + os.sep)]
print("|".join(names))' "$1")" || return 1
  local exclude="${scripts:+^($scripts)\$}"
  if [ -n "${2:-}" ]; then
    exclude="${exclude:+$exclude|}$2"
  fi
  selected=(-L core)
  if [ -n "$exclude" ]; then
    selected+=(-E "$exclude")
  fi
}

run_asan() {
  mkdir -p "$asan_dir"
  log="$asan_dir/sanitizers-asan.log"
  : >"$log"
  local t0 t1 t2
  t0=$(now)
  local selected=()
  if ! configure_asan "$asan_dir" ||
    ! step build 1200 cmake --build "$asan_dir" --parallel "$jobs" ||
    ! compiled_tests "$asan_dir"; then
    finish asan FAIL "build failed after $(($(now) - t0)) s"
    return
  fi
  t1=$(now)
  # KMP_HOT_TEAMS_MAX_LEVEL=0: LLVM's OpenMP runtime (libomp, which Clang's -fopenmp links)
  # keeps the thread teams of past parallel regions ("hot teams") for reuse and does not
  # free them at exit, which LeakSanitizer reports as leaks from inside libomp; without hot
  # teams it frees each team, so every leak reported is ours.
  KMP_HOT_TEAMS_MAX_LEVEL=0 \
    ASAN_OPTIONS="detect_leaks=1:detect_stack_use_after_return=1:strict_init_order=1" \
    UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1" \
    step test 600 ctest --test-dir "$asan_dir" "${selected[@]}" --output-on-failure \
    --parallel "$jobs" --timeout 300
  local rc=$?
  t2=$(now)
  local tests
  tests="$(grep -Eo '[0-9]+ tests failed out of [0-9]+' "$log" | tail -n 1)"
  finish asan "$([ $rc -eq 0 ] && echo PASS || echo FAIL)" \
    "build $((t1 - t0)) s, tests $((t2 - t1)) s (${tests:-no ctest summary}) [log $log]"
}

run_tsan() {
  mkdir -p "$tsan_dir"
  log="$tsan_dir/sanitizers-tsan.log"
  : >"$log"
  local t0 t1 t2
  t0=$(now)
  # Archer ships with the libomp of the clang in use: <llvm>/lib/libarcher.so.
  local llvm archer
  llvm="$(dirname "$(readlink -f "$(command -v clang++)")")/.."
  archer="$(readlink -f "$llvm/lib/libarcher.so" 2>/dev/null)"
  if [ -z "$archer" ] || [ ! -f "$archer" ]; then
    finish tsan FAIL "libarcher.so not found next to $(command -v clang++) (package libomp-dev)"
    return
  fi
  local selected=()
  if ! configure "$tsan_dir" clang clang++ -DMTPT_SANITIZER=thread -DMTPT_BUILD_FUZZERS=OFF ||
    ! step build 1200 cmake --build "$tsan_dir" --parallel "$jobs" ||
    ! compiled_tests "$tsan_dir" "${MTPT_TSAN_EXCLUDE:-}"; then
    finish tsan FAIL "build failed after $(($(now) - t0)) s"
    return
  fi
  t1=$(now)
  local tsan_env=(env OMP_NUM_THREADS=4 OMP_TOOL_LIBRARIES="$archer"
    TSAN_OPTIONS="ignore_noninstrumented_modules=1 second_deadlock_stack=1 history_size=4")
  local prefix=()
  # TSan of LLVM 14 cannot map its shadow memory with the high mmap ASLR entropy of newer
  # kernels ("unexpected memory mapping"); without ASLR it can.
  if ! "${tsan_env[@]}" "$tsan_dir/Testing/Core/mtpt_core_tests" --gtest_list_tests \
    >/dev/null 2>&1; then
    prefix=(setarch "$(uname -m)" -R)
    echo "== TSan cannot start with ASLR on: running under ${prefix[*]}" >>"$log"
  fi
  # -V keeps every test's output in the log: Archer announces itself there (verbose=1).
  step test 600 "${prefix[@]}" "${tsan_env[@]}" ARCHER_OPTIONS=verbose=1 \
    ctest --test-dir "$tsan_dir" "${selected[@]}" -V --parallel "$jobs" \
    --timeout 300
  local rc=$?
  t2=$(now)
  local tests races archer_runs
  tests="$(grep -Eo '[0-9]+ tests failed out of [0-9]+' "$log" | tail -n 1)"
  races="$(grep -c 'WARNING: ThreadSanitizer' "$log")"
  archer_runs="$(grep -c 'Archer detected OpenMP application with TSan' "$log")"
  # Without Archer, TSan would not know OpenMP's barriers: a pass would mean nothing.
  if [ "$archer_runs" -eq 0 ]; then
    echo "== Archer ($archer) never attached to the OpenMP runtime" >>"$log"
    rc=1
  fi
  local details="build $((t1 - t0)) s, tests $((t2 - t1)) s (${tests:-no ctest summary};"
  details="$details $races TSan reports; Archer in $archer_runs test processes;"
  details="$details OMP_NUM_THREADS=4) [log $log]"
  finish tsan "$([ $rc -eq 0 ] && echo PASS || echo FAIL)" "$details"
}

run_fuzz() {
  mkdir -p "$fuzz_dir"
  log="$fuzz_dir/sanitizers-fuzz.log"
  : >"$log"
  local t0 t1 t2
  t0=$(now)
  # The asan phase's build, unless FUZZ_BUILD_DIR names another (then built here).
  if ! configure_asan "$fuzz_dir" ||
    ! step build 1200 cmake --build "$fuzz_dir" --parallel "$jobs" --target mtpt_fuzz_frame; then
    finish fuzz FAIL "build failed after $(($(now) - t0)) s"
    return
  fi
  t1=$(now)
  # New inputs go to the first (work) folder; the checked-in seeds stay untouched.
  local work="$fuzz_dir/corpus" artifacts="$fuzz_dir/artifacts/"
  mkdir -p "$work" "$artifacts"
  local marker="$fuzz_dir/.fuzz-start"
  touch "$marker"
  # KMP_BLOCKTIME=0: OpenMP threads sleep at once between the many tiny parallel regions
  # instead of spinning (the fuzzer runs up to 3 threads on 2 cores).
  # MTPT_FUZZ_FLAGS: more libFuzzer flags, e.g. "-fork=2 -ignore_crashes=1" for a long run
  # that collects every distinct failure instead of stopping at the first.
  local extra=()
  read -r -a extra <<<"${MTPT_FUZZ_FLAGS:-}"
  KMP_BLOCKTIME=0 step fuzz $((fuzz_seconds + 300)) \
    "$fuzz_dir/Testing/Fuzz/mtpt_fuzz_frame" -max_total_time="$fuzz_seconds" -timeout=10 \
    -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$artifacts" "${extra[@]}" \
    "$work" "$here/Testing/Fuzz/corpus/FuzzFrame"
  local rc=$?
  t2=$(now)
  # Failing inputs of this run (with -ignore_crashes=1 libFuzzer may go on and exit 0).
  local found
  found="$(find "$artifacts" -type f -newer "$marker" | wc -l)"
  if [ "$found" -gt 0 ] && [ $rc -eq 0 ]; then
    rc=1
  fi
  local runs rate corpus
  runs="$(grep -Eo 'stat::number_of_executed_units: *[0-9]+' "$log" | grep -Eo '[0-9]+$')"
  rate="$(grep -Eo 'stat::average_exec_per_sec: *[0-9]+' "$log" | grep -Eo '[0-9]+$')"
  if [ -z "$runs" ]; then # fork mode: the parent's last status line, "#<executions>: ..."
    runs="$(grep -Eo '^#[0-9]+:' "$log" | tail -n 1 | tr -d '#:')"
    [ -n "$runs" ] && rate=$((runs / (t2 - t1 > 0 ? t2 - t1 : 1)))
  fi
  corpus="$(find "$work" -type f | wc -l)"
  local details="build $((t1 - t0)) s, fuzz $((t2 - t1)) s: ${runs:-?} executions"
  details="$details (${rate:-?}/s), work corpus $corpus inputs [log $log]"
  if [ "$found" -gt 0 ]; then
    local input
    input="$(ls -t "$artifacts" | head -n 1)"
    details="$details; $found failing inputs, reproduce the newest: MTPT_FUZZ_VERBOSE=1"
    details="$details $fuzz_dir/Testing/Fuzz/mtpt_fuzz_frame $artifacts$input"
  elif [ $rc -ne 0 ]; then
    details="$details; exit status $rc, no failing input saved"
  fi
  finish fuzz "$([ $rc -eq 0 ] && echo PASS || echo FAIL)" "$details"
}

start=$(now)
for phase in $phases; do
  case "$phase" in
    asan) run_asan ;;
    tsan) run_tsan ;;
    fuzz) run_fuzz ;;
    *)
      echo "sanitizers: unknown phase '$phase'" >&2
      exit 2
      ;;
  esac
done
echo "sanitizers: summary ($(($(now) - start)) s in all):"
printf '  %s\n' "${summary[@]}"
exit "$failed"
