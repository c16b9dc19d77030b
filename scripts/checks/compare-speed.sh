#!/usr/bin/env bash
# Times MTPT's whole frames with two builds, alternating in one run, on the scenes of
# Documentation/results/frames.csv (the wavelet at 16, 512 and 1024 pixels; the blunt fin,
# the combustor, kiefer and the fire at 1024), and prints each figure's median over the
# rounds for both builds with their ratio (after / before). mtpt_bench_frames times each
# frame with the camera turning before it, in VTK's default window and single-sampled.
#
# Usage: scripts/checks/compare-speed.sh BEFORE-BUILD AFTER-BUILD OUT-DIR [ROUNDS]
#   BUILD folders hold Release builds with their benchmarks (BUILD/Benchmarks/
#   mtpt_bench_frames); ROUNDS defaults to 3. The real meshes come from MTPT_DATA_DIR
#   (default ../shared/data beside this checkout). Each build's rows are kept in
#   OUT-DIR/before.csv and OUT-DIR/after.csv.
set -euo pipefail
usage="usage: $0 BEFORE-BUILD AFTER-BUILD OUT-DIR [ROUNDS]"
before="$(cd "${1:?$usage}" && pwd)"
after="$(cd "${2:?$usage}" && pwd)"
out="${3:?$usage}"
rounds="${4:-3}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
export MTPT_DATA_DIR="${MTPT_DATA_DIR:-$here/../shared/data}"
mkdir -p "$out"
rm -f "$out/before.csv" "$out/after.csv"

scenes=("wavelet 16" "wavelet 512" "wavelet 1024" "bluntfin 1024" "comb 1024" "kiefer 1024"
  "fire_ug 1024")
for round in $(seq "$rounds"); do
  for scene in "${scenes[@]}"; do
    read -r mesh size <<<"$scene"
    for side in before after; do
      build="$before"
      [ "$side" = after ] && build="$after"
      echo "compare-speed: round $round, $mesh at $size, $side" >&2
      "$here/Testing/xvfb-launch.sh" "$build/Benchmarks/mtpt_bench_frames" --meshes "$mesh" \
        --sizes "$size" --contenders mtpt-cpu --repeat 5 --csv "$out/$side.csv" >/dev/null
    done
  done
done

python3 - "$out/before.csv" "$out/after.csv" <<'EOF'
import csv
import statistics
import sys

def rows(path):
    figures = {}
    with open(path, encoding="utf-8") as f:
        for row in csv.DictReader(f):
            key = (row["mesh"], int(row["width"]), row["multisampling"], row["shading"])
            for name in ("ms", "cpu_stages_ms", "composite_ms"):
                figures.setdefault(key + (name,), []).append(float(row[name]))
    return figures

before, after = rows(sys.argv[1]), rows(sys.argv[2])
print("| mesh | size | multisampling | shading | figure | before (median) | after (median) | after / before |")
print("|---|---:|---|---|---|---:|---:|---:|")
for key in sorted(before):
    if key not in after:
        continue
    b, a = statistics.median(before[key]), statistics.median(after[key])
    ratio = a / b if b > 0 else float("nan")
    print(f"| {key[0]} | {key[1]} | {key[2]} | {key[3]} | {key[4]} | {b:.1f} | {a:.1f} | {ratio:.3f} |")
EOF
