#!/usr/bin/env bash
# Tables 3.1/3.2 on the simulator, end to end (docs/markers.md): the book's calibration
# of the simulated scope (white background, square chart, two-dot marker: ch. 2/3),
# then each strip-marker suite through `endotower sim` with analysis.markers, scored by
# `endotower eval` against the goals (depth <= 3 %, x and y <= 5 % mean error).
# Usage: toolchain/marker-suite.sh [OUT_DIR] [SCALE]   (default out/markers, 1; the
# book's 10 frames per point: SCALE 10). Needs a release build.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bin="$root/build/release/firmware/endotower"
out=${1:-$root/out/markers}
scale=${2:-1}
scenarios="$root/board/sim/scenarios"
mkdir -p "$out"

# Rendered calibration frames, renamed by their distance (070mm.png) as calibrate wants.
by_distance() {  # scenario, dir
    "$bin" scene --scenario "$1" --out "$2.render" >/dev/null
    mkdir -p "$2"
    python3 - "$2.render" "$2" <<'PY'
import json, os, shutil, sys
src, dst = sys.argv[1], sys.argv[2]
for i, line in enumerate(open(os.path.join(src, "truth.jsonl"))):
    d = json.loads(line)["target"]["distance_mm"]
    shutil.copy(os.path.join(src, "frames", "%06d.png" % i), os.path.join(dst, "%03.0fmm.png" % d))
PY
    rm -rf "$2.render"
}
rm -rf "$out/white" "$out/chart" "$out/marker"
"$bin" scene --scenario "$scenarios/fig26_white.yaml" --out "$out/white.render" >/dev/null
mv "$out/white.render/frames" "$out/white" && rm -rf "$out/white.render"
by_distance "$scenarios/markers/calib_chart.yaml" "$out/chart"
by_distance "$scenarios/fig33_two_dot.yaml" "$out/marker"
"$bin" calibrate --images "$out/chart" --target squares --spacing 8 --model book --white "$out/white" \
    --marker "$out/marker" --scope sim-book --out "$out/scope.json" >"$out/calibrate.txt"

status=0
for suite in t32_entry0 t32_entry45; do
    "$bin" scene --scenario "$scenarios/markers/$suite.yaml" --scale "$scale" --out "$out/$suite" >/dev/null
    cat >"$out/$suite.board.yaml" <<YAML
board: sim
calibration: scope.json
analysis:
  stage: none
  tracker: none
  tool_diameter_mm: 5
  markers: true
sim:
  input: $suite/frames
  output: $suite/out.mkv
  trace: $suite/trace.jsonl
YAML
    "$bin" sim --board "$out/$suite.board.yaml" >/dev/null
    echo "== $suite"
    "$bin" eval --trace "$out/$suite/trace.jsonl" --truth "$out/$suite/truth.jsonl" \
        --max-marker-depth-error 3% --max-marker-xy-error 5% | sed -n '/^markers/,$p' || status=1
done
exit $status
