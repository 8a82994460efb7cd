#!/usr/bin/env bash
# Gesture commands of the SCI end to end (docs/sci.md "Gesture commands"): TRIALS
# rendered scenes, each one intended command, replayed through `endotower sim` with the
# likelihood tracker, the shipped gesture model and the ring menu (fig. 3.34b); the
# trace must show the command and nothing else. Three kinds, in turn:
#   confirm  the handle's button activates; a grasper moves onto a ring item, opens its
#            jaws and holds still (select, fig. 3.32), then loops (confirm): the item's
#            action (its image viewer, or Exit).
#   deny     the same, but a straight stroke instead of the loop: deny 2.0 s after the
#            select, no action (fig. 3.33b).
#   cross    no handle event; two closed tools come together, cross and hold still: the
#            quadrant menu (fig. 3.34a); they part and cross again: deactivate.
# Each trial draws (deterministically from its number) the item, the tool's entry
# direction, diameter (5 or 10 mm), depth (55-85 mm), light (0.5-1.0), tissue seed, and
# for the loop its radius (3-5 mm) and duration (0.9-1.4 s). Prints one line per trial
# and the success per kind; the time to select is from the frame the tool starts
# towards the item to the frame its command takes effect (confirm or exit).
# Usage: [ENDOTOWER=BINARY] [FIRST=K] [GESTURES=MODEL] [KIND=K] [SCENES=DIR]
#        toolchain/sci-gesture-commands.sh [OUT_DIR] [TRIALS]
# (FIRST: the trials K..K+TRIALS-1 instead of 1..TRIALS, another sample of poses;
# GESTURES: a gesture model to measure instead of the shipped one; KIND: only the
# trials of that kind, confirm, deny or cross, are run; SCENES: each trial's rendered
# scene is kept there, and a trial already rendered there is only replayed, so another
# build or model is measured on the same frames)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$root/out/sci_gestures}
trials=${2:-30}
first=${FIRST:-1}
last=$((first + trials - 1))
bin=${ENDOTOWER:-$root/build/release/firmware/endotower}
mkdir -p "$out"
cat > "$out/board.yaml" <<EOF
board: sci_gesture_commands
analysis:
  stage: none
  tracker: likelihood
  tool_model: $root/board/sim/models/tool_likelihood.bin
  gestures:
    model: ${GESTURES:-$root/board/sim/models/gestures.yml}
    tool_model: $root/board/sim/models/gesture_tool_likelihood.bin
sci:
  layout: ring
  media: $root/board/sim/sci_media
EOF
printf 'frame 3 press\nframe 4 release\n' > "$out/button.txt"

for i in $(seq "$first" "$last"); do
    if [ -n "${KIND:-}" ] && [ "$(python3 "$root/toolchain/sci_gesture_trial.py" kind "$i")" != "$KIND" ]; then
        continue
    fi
    t=$out/trial_$i
    if [ ! -f "$t.jsonl" ]; then
        mkdir -p "$t"
        python3 "$root/toolchain/sci_gesture_trial.py" scenario "$i" > "$t/scenario.yaml"
        events=$(python3 "$root/toolchain/sci_gesture_trial.py" kind "$i")
        [ "$events" = cross ] && events="" || events=$out/button.txt
        scene=${SCENES:+$SCENES/trial_$i}
        scene=${scene:-$t/scene}
        [ -f "$scene/truth.jsonl" ] || "$bin" scene --scenario "$t/scenario.yaml" --out "$scene" > /dev/null
        "$bin" sim --board "$out/board.yaml" --input "$scene/frames" --events "$events" \
            --out "$t/o.avi" --trace "$t.jsonl.part" > /dev/null
        mv "$t.jsonl.part" "$t.jsonl"
        rm -rf "$t/scene" "$t/o.avi"
    fi
done
python3 "$root/toolchain/sci_gesture_trial.py" score "$out" "$first" "$last"
