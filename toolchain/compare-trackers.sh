#!/bin/sh
# Every tracker on the table 4.1 simulator suites and on ../shared/data/sznitman_lap
# with `endotower eval` (docs/tracking.md, "Comparison"): success and the median
# analysis time per frame (the trace's stages_us.analysis; stage none, so only the
# tracker). Usage: toolchain/compare-trackers.sh [BUILD_DIR] [WORK_DIR] [TRACKER ...]
set -eu
B=${1:-build/release}/firmware/endotower
W=${2:-/tmp/compare-trackers}
shift 2 2>/dev/null || shift $#
TRACKERS=${*:-likelihood kalman kalman_red ekf mog2 mhi particle particle_sorted hybrid}
SUITES="t41_speed_0_4 t41_speed_4_8 t41_speed_8_up t41_light_0_30 t41_light_30_45 t41_light_46_100 t41_distractors two_tools_crossing tool_leaves"
mkdir -p "$W"
for s in $SUITES; do
    [ -f "$W/$s/truth.jsonl" ] || "$B" scene --scenario "board/sim/scenarios/$s.yaml" --out "$W/$s" >/dev/null
done
median_ms() {  # median of stages_us.analysis over a trace, in ms
    python3 -c 'import json,sys
v=sorted(json.loads(l)["stages_us"].get("analysis",0) for l in open(sys.argv[1]))
print("%.1f" % (v[len(v)//2]/1000.0))' "$1"
}
for t in $TRACKERS; do
    printf 'board: t\nanalysis: {stage: none, tracker: %s, tool_model: %s/board/sim/models/tool_likelihood.bin}\n' "$t" "$(pwd)" > "$W/$t.yaml"
    for s in $SUITES; do
        "$B" sim --board "$W/$t.yaml" --input "$W/$s/frames" --trace "$W/$t-$s.jsonl" --out "$W/$t-$s.mp4" --events '' >/dev/null
        printf '%s %s %s ms ' "$t" "$s" "$(median_ms "$W/$t-$s.jsonl")"
        "$B" eval --trace "$W/$t-$s.jsonl" --truth "$W/$s/truth.jsonl" | grep -iE 'success|identity|reacq' | tr '\n' ' '
        echo
    done
    if [ -d ../shared/data/sznitman_lap/frames ]; then
        "$B" sim --board "$W/$t.yaml" --input ../shared/data/sznitman_lap/frames --trace "$W/$t-sz.jsonl" --out "$W/$t-sz.mp4" --events '' >/dev/null
        printf '%s sznitman_lap %s ms ' "$t" "$(median_ms "$W/$t-sz.jsonl")"
        "$B" eval --trace "$W/$t-sz.jsonl" --sznitman ../shared/data/sznitman_lap/train.xml | grep -iE 'success' | tr '\n' ' '
        echo
    fi
done
