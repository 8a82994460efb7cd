#!/usr/bin/env bash
# The gesture trials of docs/gestures.md (table 3.3 layout, the 1 s hold): renders the
# fig. 3.22 (grasper, scissors) and fig. 3.23 suites at --scale 15 (30 frames = 1.2 s
# per state), replays them with only the gesture stage on and scores the traces with
# 'endotower eval'; prints each suite's summary and confusion table.
# Usage: [ENDOTOWER=BINARY] [SUITES="..."] toolchain/gesture-trials.sh [OUT] [MODEL]
#   SUITES scenarios under board/sim/scenarios, without .yaml (default the three above;
#          e.g. "gestures/test_random40_double": the random poses, docs/gestures.md)
#   OUT    work and report folder (default build/gesture-eval)
#   MODEL  gesture model (default board/sim/models/gestures.yml, the shipped one)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=$(realpath -m "${1:-$root/build/gesture-eval}")
model=$(realpath "${2:-$root/board/sim/models/gestures.yml}")
bin=${ENDOTOWER:-$root/build/release/firmware/endotower}
[ -x "$bin" ] || "$root/toolchain/build.sh" release
# Another build's binary (ENDOTOWER) replays the frames already rendered in OUT.
mkdir -p "$out"
cat >"$out/board.yaml" <<BOARD
board: gesture-trials
analysis:
  stage: none
  tracker: none
  tool_model: $root/board/sim/models/tool_likelihood.bin
  gestures:
    model: $model
    tool_model: $root/board/sim/models/gesture_tool_likelihood.bin
    hold_ms: 1000
BOARD
for scenario in ${SUITES:-fig322_grasper_orientations fig322_scissors_orientations fig323_double_gestures}; do
  s=$(basename "$scenario")
  [ -f "$out/$s/truth.jsonl" ] ||
    "$bin" scene --scenario "$root/board/sim/scenarios/$scenario.yaml" --scale 15 --out "$out/$s" >/dev/null
  "$bin" sim --board "$out/board.yaml" --input "$out/$s/frames" --trace "$out/$s.jsonl" \
    --out "$out/$s.mkv" >/dev/null
  "$bin" eval --trace "$out/$s.jsonl" --truth "$out/$s/truth.jsonl" --report "$out/report_$s" |
    grep '^gestures:'
  sed -n '/^| Performed/,/^$/p' "$out/report_$s/report.md"
done
