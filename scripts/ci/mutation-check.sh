#!/usr/bin/env bash
# Checks that the image tests can see the visibility order: runs a fixed sample of them with
# the cells drawn in a deliberately wrong order and requires every test of the sample to
# fail under each wrong order (a test that passes with a wrong order does not test it):
#   reversed: front to back instead of back to front   (MTPT_TESTING_ORDER=reversed)
#   storage:  the cells as stored, not sorted at all     (MTPT_TESTING_ORDER=storage)
# Prints, for each order, how many of the sample failed, and names any that passed.
#
# The sample covers each way a frame reaches the screen, chosen among the tests that compare
# an image with VTK's PT or the exact reference, fastest first: both backends with each
# shading, clipping planes, several blocks in one order, frames that reuse earlier work, a
# user transform, a wide perspective view with opaque geometry, dependent components and a
# component of a vector array. `bash scripts/ci/mutation-check.sh build all` runs every
# rendering test instead and requires at least MIN_FAILURES (default 10) to fail: the
# survey, which takes about ten times as long. The sample runs in as many processes as the
# machine has cores (gtest's sharding).
#
# Usage: scripts/ci/mutation-check.sh [build-dir] [all]   (default: build; from scripts/test.sh)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
. "$here/scripts/ci/gtest-shards.sh"
build="${1:-$here/build}"
mode="${2:-sample}"
[ -d "$build" ] && build="$(cd "$build" && pwd)"
tests="$build/Testing/Rendering/mtpt_rendering_tests"
min_failures="${MIN_FAILURES:-10}"
[ -x "$tests" ] || { echo "mutation-check: $tests not built (run scripts/test.sh)" >&2; exit 1; }
cd "$build/Testing/Rendering" # as ctest runs it: the images it writes land in the build tree

sample=(
  Backends/MapperWork.FramesReuseExactlyWhatDidNotChange/CPU
  Backends/MapperWork.FramesReuseExactlyWhatDidNotChange/OpenGL
  Backends/MapperShading.MatchesTheExactReference/cpu
  Backends/MapperShading.MatchesTheExactReference/gl
  Backends/MapperClippingPlanes.EachShadingMatchesTheExactReference/CPU
  Backends/MapperClippingPlanes.EachShadingMatchesTheExactReference/OpenGL
  Backends/MapperComposite.InterleavedBlocksMatchTheMergedGridAndItsExactReference/CPU
  MapperImages.BaselineSyntheticPerspective
  MapperImages.BaselineRealMeshOrthographic
  MapperImages.SyntheticOrthographicMatchesVTK
  MapperImages.TransformedVolumeMatchesVTK
  MapperHardCases.WideViewAndOpaqueVolumeAgainstTheReference
  MapperDependentComponents.TwoComponentsMatchVTK
  MapperVTKScenarios.ColouredByOneComponentOfAVectorArrayChosenByName
)
case "$mode" in
sample) filter="$(IFS=:; echo "${sample[*]}")" ;;
all) filter="*" ;;
*) echo "mutation-check: the second argument is 'all' or nothing" >&2; exit 2 ;;
esac
shards="$(nproc)"

status=0
for order in reversed storage; do
  # The test program fails, as it must: its output is what counts.
  run_gtest_shards "$shards" "$build/mutation-$order" env MTPT_TESTING_ORDER="$order" \
    timeout 900 "$here/Testing/xvfb-launch.sh" "$tests" --gtest_brief=1 --gtest_filter="$filter"
  logs=("$build"/mutation-"$order"-*.log)
  failed="$(cat "${logs[@]}" | grep -E '^\[  FAILED  \] [A-Za-z]' |
    sed -E 's/^\[  FAILED  \] //; s/ \([0-9]+ ms\)$//; s/, where GetParam.*$//' | sort -u ||
    true)"
  count="$(printf '%s' "$failed" | grep -c . || true)"
  ran="$(cat "${logs[@]}" | grep -oE '^\[==========\] [0-9]+ tests?' | grep -oE '[0-9]+' |
    awk '{ s += $1 } END { print s + 0 }' || true)"
  echo "mutation-check: order '$order': $count of ${ran:-0} tests failed"
  if [ "$mode" = all ]; then
    printf '%s\n' "$failed" | sed 's/^/  /'
    if [ "$count" -lt "$min_failures" ]; then
      echo "mutation-check: order '$order' failed fewer than $min_failures tests: the image" \
        "tests do not see the visibility order (logs: $build/mutation-$order-*.log)" >&2
      status=1
    fi
    continue
  fi
  if [ "${ran:-0}" != "${#sample[@]}" ]; then
    echo "mutation-check: ran ${ran:-0} of the sample's ${#sample[@]} tests: a test was" \
      "renamed or removed (logs: $build/mutation-$order-*.log)" >&2
    status=1
  fi
  for name in "${sample[@]}"; do
    if ! printf '%s\n' "$failed" | grep -qxF "$name"; then
      echo "mutation-check: $name passed with the order '$order': it does not see the" \
        "visibility order (logs: $build/mutation-$order-*.log)" >&2
      status=1
    fi
  done
done
exit "$status"
