#!/usr/bin/env bash
# The gesture trials of docs/gestures.md (table 3.3 layout, the 1 s hold): renders the
# fig. 3.22 (grasper, scissors) and fig. 3.23 suites at --scale 15 (30 frames = 1.2 s
# per state), replays them with only the gesture stage on and scores the traces with
# 'endotower eval'; prints each suite's summary and confusion table, and with more than
# one suite the table of all of them together (their traces and truths joined, frames
# renumbered: OUT/all, OUT/report_all).
# Usage: [ENDOTOWER=BINARY] [SUITES="..."] [KEEP_VIDEO=1] toolchain/gesture-trials.sh [OUT] [MODEL]
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
joined=()
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
  # The replayed video is not scored (a random40 suite's is 800 MB): kept only with
  # KEEP_VIDEO=1.
  [ "${KEEP_VIDEO:-0}" = 1 ] || rm -f "$out/$s.mkv"
  joined+=("$out/$s.jsonl" "$out/$s/truth.jsonl")
done
[ "${#joined[@]}" -gt 2 ] || exit 0
# Every suite's trials in one table: frames renumbered, and each trace's clock moved past
# the one before it so the joined trace's times keep increasing (the holds and fires are
# each suite's own, from its replay).
mkdir -p "$out/all"
python3 - "$out/all" "${joined[@]}" <<'PY'
import json, os, sys
out, paths = sys.argv[1], sys.argv[2:]
names = [f"{out}/trace.jsonl", f"{out}/truth.jsonl"]
try:
    with open(names[0] + ".tmp", "w") as trace, open(names[1] + ".tmp", "w") as truth:
        frame, clock = 0, 0
        for trace_path, truth_path in zip(paths[0::2], paths[1::2]):
            steps = [json.loads(l) for l in open(trace_path)]
            truths = [json.loads(l) for l in open(truth_path)]
            if len(steps) != len(truths):
                raise ValueError(f"{trace_path}: {len(steps)} frames, {truth_path}: {len(truths)}")
            for t in truths:
                t["frame"] += frame
                truth.write(json.dumps(t) + "\n")
            for s in steps:
                s["frame"] += frame
                s["seq"] += frame
                s["capture_ns"] += clock
                s["present_ns"] += clock
                trace.write(json.dumps(s) + "\n")
            frame += len(steps)
            clock += steps[-1]["capture_ns"] + 10**9
except (OSError, ValueError, KeyError) as e:  # nothing half-written is left behind
    for n in names:
        if os.path.exists(n + ".tmp"):
            os.remove(n + ".tmp")
    sys.exit(f"gesture-trials: joining the suites: {e}")
for n in names:
    os.replace(n + ".tmp", n)
PY
echo "all suites:"
"$bin" eval --trace "$out/all/trace.jsonl" --truth "$out/all/truth.jsonl" --report "$out/report_all" |
  grep '^gestures:'
sed -n '/^| Performed/,/^$/p' "$out/report_all/report.md"
