#!/usr/bin/env bash
# Trains the shipped per-pixel tool model (board/sim/models/tool_likelihood.bin) from
# simulator scenes rendered with a seed the test suites never use (9001), plus the one
# real image with an MIT licence (../shared/data/endotip). Deterministic: same bytes
# every run. sznitman_lap and endovis17 are never used for training (held out).
# --gestures: the gesture segmenter's model (board/sim/models/gesture_tool_likelihood.bin,
# analysis.gestures.tool_model) from the same scenes plus the gesture training scenes
# (board/sim/scenarios/gestures/train_*.yaml at seed 9006, the gesture model's training
# seed) and without the real image: that image's tools reflect the pink tissue, and at
# its weight the model calls the pale pink sheen of wet tissue "tool"; the sheen joins
# the shaft and the gesture region is lost (docs/gestures.md, "The segmenter's own pixel
# model").
# Usage: toolchain/train-tool-model.sh [--gestures] [OUT]   (default: the shipped model)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
gestures=false
if [ "${1:-}" = --gestures ]; then gestures=true; shift; fi
if $gestures; then
  out=${1:-$root/board/sim/models/gesture_tool_likelihood.bin}
else
  out=${1:-$root/board/sim/models/tool_likelihood.bin}
fi
bin=$root/build/release/firmware/endotower
[ -x "$bin" ] || "$root/toolchain/build.sh" release
work=$root/build/tool-model-train
mkdir -p "$work"
args=()
for s in t41_speed_0_4 t41_speed_4_8 t41_speed_8_up t41_light_0_30 t41_light_30_45 t41_light_46_100 \
         t41_distractors two_tools_crossing disturbances hd_overview; do
  "$bin" scene --scenario "$root/board/sim/scenarios/$s.yaml" --seed 9001 --labels --size 640x480 --out "$work/$s" >/dev/null
  args+=(--scene "$work/$s")
done
real=$root/../shared/data/endotip
if $gestures; then
  for f in "$root"/board/sim/scenarios/gestures/train_*.yaml; do
    s=$(basename "$f" .yaml)
    "$bin" scene --scenario "$f" --seed 9006 --labels --size 640x480 --out "$work/$s" >/dev/null
    args+=(--scene "$work/$s")
  done
elif [ -f "$real/demo.jpg" ]; then
  args+=(--image "$real/demo.jpg" --mask "$real/demo_seg.png")
else
  echo "train-tool-model: $real absent: training on the simulator only" >&2
fi
mkdir -p "$(dirname "$out")"
"$bin" train-tool-model "${args[@]}" --out "$out"
