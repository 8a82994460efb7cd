#!/usr/bin/env bash
# False activations of the SCI on ordinary surgery motion (docs/sci.md): replays
# recordings with no handle events through `endotower sim` with the sim board (the
# likelihood tracker, gestures, sci on) and counts, from the traces, the frames whose
# "sci" event is an activation (activate_hold, quadrant, activate_button) and the
# near misses (activation_start: scissors seen still in the activation area) and the
# longest time spent activating (the hold needs 3 s).
# Inputs: the real cholecystectomy clip ../shared/data/sznitman_lap (skipped when
# absent), the bundled clip, and the table 4.1 scene suites rendered at FRAMES frames
# each (default 125 = 5 s at 25 fps; longer than the 3 s hold), and SURGERY chunks of
# board/sim/scenarios/surgery_motion.yaml (two tools working, crossing, holding; 1500
# frames = 60 s each, seeds 1..SURGERY; frames deleted after the replay, traces kept).
# Usage: [ENDOTOWER=BINARY] [SURGERY=N | SEEDS="K ..."] [GESTURES=MODEL] [SCENES=DIR]
#        toolchain/sci-false-activations.sh [OUT_DIR] [FRAMES]
# (SEEDS: those surgery chunks instead of 1..N; GESTURES: a gesture model to measure
# instead of the shipped one)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$root/out/sci_false}
frames=${2:-125}
bin=${ENDOTOWER:-$root/build/release/firmware/endotower}
mkdir -p "$out"
# The sim board, or the same with another gesture model (GESTURES=MODEL) to measure.
board=$root/board/sim/board.yaml
if [ -n "${GESTURES:-}" ]; then
    board=$out/board.yaml
    sed -e "s|^\(    model: \)models/gestures.yml|\1$(realpath "$GESTURES")|" \
        -e "s|: models/|: $root/board/sim/models/|; s|: sci_media|: $root/board/sim/sci_media|" \
        -e "s|: media/|: $root/board/sim/media/|" \
        "$root/board/sim/board.yaml" > "$board"
fi
inputs=()
data=$root/../shared/data/sznitman_lap/frames
if [ -d "$data" ]; then inputs+=("sznitman_lap=$data"); else echo "skip: $data absent"; fi
inputs+=("endotip_rotation=$root/board/sim/media/endotip_rotation.mp4")
for s in t41_speed_0_4 t41_speed_4_8 t41_speed_8_up t41_distractors t41_light_0_30 two_tools_crossing; do
    [ -d "$out/scene_$s" ] || "$bin" scene --scenario "$root/board/sim/scenarios/$s.yaml" --frames "$frames" \
        --out "$out/scene_$s" >/dev/null
    inputs+=("$s=$out/scene_$s/frames")
done
seeds=${SEEDS:-$(seq 1 "${SURGERY:-0}")}
# SCENES=DIR keeps the rendered chunks there (650 MB each; rendering is 85 % of a
# chunk's time), so another model is measured on the same frames by replays alone.
scenes=${SCENES:-$out}
for k in $seeds; do
    inputs+=("surgery_$k=$scenes/scene_surgery_$k/frames")
done
total_s=0
total_act=0
printf "%-20s %8s %12s %12s %16s  %s\n" input seconds activations near_misses longest_hold_s gestures_fired
for entry in "${inputs[@]}"; do
    name=${entry%%=*}
    input=${entry#*=}
    if [[ -f $out/$name.jsonl.sum ]]; then
        read -r s a < "$out/$name.jsonl.sum"   # already replayed (a surgery chunk's frames may be gone)
        total_s=$(python3 -c "print($total_s + $s)")
        total_act=$((total_act + a))
        continue
    fi
    if [[ $name == surgery_* && ! -f $scenes/scene_$name/truth.jsonl ]]; then
        "$bin" scene --scenario "$root/board/sim/scenarios/surgery_motion.yaml" --seed "${name#surgery_}" --frames 1500 \
            --out "$scenes/scene_$name" >/dev/null
    fi
    "$bin" sim --board "$board" --input "$input" --events "" --out "$out/$name.avi" \
        --trace "$out/$name.jsonl" >/dev/null
    python3 - "$out/$name.jsonl" "$name" <<'PY'
import json, sys
lines = [json.loads(l) for l in open(sys.argv[1])]
events = [l.get("sci", {}).get("event") for l in lines]
act = sum(e in ("activate_hold", "quadrant", "activate_button") for e in events)
near = sum(e == "activation_start" for e in events)
# The longest run of "activating" frames: how close it came to the 3 s hold.
longest = run = 0
for l in lines:
    run = run + 1 if l.get("sci", {}).get("state") == "activating" else 0
    longest = max(longest, run)
period = (lines[1]["capture_ns"] - lines[0]["capture_ns"]) / 1e9
secs = (lines[-1]["capture_ns"] - lines[0]["capture_ns"]) / 1e9 + (lines[1]["capture_ns"] - lines[0]["capture_ns"]) / 1e9
# Gestures held long enough to fire (a cross fired is the quadrant menu's trigger).
fired = {}
for l in lines:
    g = l.get("gesture") or {}
    if g.get("fired"):
        fired[g["label"]] = fired.get(g["label"], 0) + 1
print("%-20s %8.2f %12d %12d %16.2f  %s" % (sys.argv[2], secs, act, near, longest * period,
      " ".join("%s=%d" % kv for kv in sorted(fired.items())) or "-"))
open(sys.argv[1] + ".sum", "w").write("%f %d\n" % (secs, act))
PY
    [[ $name == surgery_* ]] && rm -f "$out/$name.avi"
    [[ $name == surgery_* && -z ${SCENES:-} ]] && rm -rf "$out/scene_$name"
    read -r s a < "$out/$name.jsonl.sum"
    total_s=$(python3 -c "print($total_s + $s)")
    total_act=$((total_act + a))
done
python3 -c "s=$total_s; a=$total_act; print('total: %.1f s, %d activations = %.1f false activations per hour' % (s, a, a * 3600 / s))"
