#!/bin/sh
# Every tracker on the table 4.1 simulator suites and on ../shared/data/sznitman_lap
# with `endotower eval` (docs/tracking.md, "Comparison"): success and the median
# analysis time per frame (the trace's stages_us.analysis; stage none, so only the
# tracker; SUITES=... picks suites, REAL=0 skips the real clip). csrt and kcf:
# OpenCV's trackers from the truth's box (endotower baseline).
# Usage: toolchain/compare-trackers.sh [BUILD_DIR] [WORK_DIR] [TRACKER ...]
set -eu
B=${1:-build/release}/firmware/endotower
W=${2:-/tmp/compare-trackers}
shift 2 2>/dev/null || shift $#
TRACKERS=${*:-likelihood kalman kalman_red ekf mog2 mhi particle particle_sorted hybrid csrt kcf}
SUITES=${SUITES:-"t41_speed_0_4 t41_speed_4_8 t41_speed_8_up t41_light_0_30 t41_light_30_45 t41_light_46_100 t41_distractors two_tools_crossing tool_leaves"}
mkdir -p "$W"
for s in $SUITES; do
    [ -f "$W/$s/truth.jsonl" ] || "$B" scene --scenario "board/sim/scenarios/$s.yaml" --out "$W/$s" >/dev/null
done
median_ms() {  # median of stages_us.analysis over a trace's frames that ran the tracker, in ms
    python3 -c 'import json,sys
v=sorted(u for u in (json.loads(l)["stages_us"].get("analysis",0) for l in open(sys.argv[1])) if u > 0)
print("%.1f" % (v[len(v)//2]/1000.0) if v else "-")' "$1"
}
# tool_leaves: frames from the tool's return into view to the first frame it is
# found again by the book's rule (tip within 2 widths, axis within 20 degrees), and
# the tools reported while it is out of view.
reacquire() {
    python3 - "$1" "$2" <<'PY'
import json, math, sys
trace = [json.loads(l) for l in open(sys.argv[1])]
truth = [json.loads(l) for l in open(sys.argv[2])]
def ok(tools, t):
    for e in tools:
        d = math.hypot(e["tip_px"][0] - t["tip_px"][0], e["tip_px"][1] - t["tip_px"][1])
        a = abs((e["axis_deg"] - t["axis_deg"] + 180) % 360 - 180)
        if d <= 2 * t["width_px"] and a <= 20: return True
    return False
seen_out = False; back = None; found = None; ghosts = 0; out_frames = 0
for tr, tt in zip(trace, truth):
    t = tt["tools"][0]; tools = tr.get("tools", [])
    if not t["visible"]:
        seen_out = True; out_frames += 1; ghosts += len(tools) > 0
    elif seen_out and back is None:
        back = tt["frame"]
    if back is not None and found is None and t["visible"] and ok(tools, t):
        found = tt["frame"]
print("| out of view: tools reported in %d/%d frames | re-acquired %s" % (ghosts, out_frames,
      "after %d frames" % (found - back) if found is not None else "never"), end=" ")
PY
}
for t in $TRACKERS; do
    printf 'board: t\nanalysis: {stage: none, tracker: %s, tool_model: %s/board/sim/models/tool_likelihood.bin}\n' "$t" "$(pwd)" > "$W/$t.yaml"
    for s in $SUITES; do
        case $t in
        csrt | kcf) "$B" baseline --tracker "$t" --scene "$W/$s" --trace "$W/$t-$s.jsonl" >/dev/null ;;
        *) "$B" sim --board "$W/$t.yaml" --input "$W/$s/frames" --trace "$W/$t-$s.jsonl" --out "$W/$t-$s.mp4" --events '' >/dev/null ;;
        esac
        printf '%s %s %s ms ' "$t" "$s" "$(median_ms "$W/$t-$s.jsonl")"
        "$B" eval --trace "$W/$t-$s.jsonl" --truth "$W/$s/truth.jsonl" | grep -iE 'success|identity|false pos' | tr '\n' ' '
        [ "$s" = tool_leaves ] && reacquire "$W/$t-$s.jsonl" "$W/$s/truth.jsonl"
        echo
    done
    # The real clip has head annotations only, no box to start CSRT/KCF from.
    if [ "${REAL:-1}" = 1 ] && [ -d ../shared/data/sznitman_lap/frames ] && [ "$t" != csrt ] && [ "$t" != kcf ]; then
        "$B" sim --board "$W/$t.yaml" --input ../shared/data/sznitman_lap/frames --trace "$W/$t-sz.jsonl" --out "$W/$t-sz.mp4" --events '' >/dev/null
        printf '%s sznitman_lap %s ms ' "$t" "$(median_ms "$W/$t-sz.jsonl")"
        "$B" eval --trace "$W/$t-sz.jsonl" --sznitman ../shared/data/sznitman_lap/train.xml | grep -iE 'success' | tr '\n' ' '
        echo
    fi
done
