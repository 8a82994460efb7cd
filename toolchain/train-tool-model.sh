#!/usr/bin/env bash
# Trains the shipped per-pixel tool model (board/sim/models/tool_likelihood.bin) from
# simulator scenes rendered with a seed the test suites never use (9001), plus the one
# real image with an MIT licence (../shared/data/endotip). Deterministic: same bytes
# every run. sznitman_lap and endovis17 are never used for training (held out).
# Usage: toolchain/train-tool-model.sh [OUT]   (default: the shipped model)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$root/board/sim/models/tool_likelihood.bin}
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
if [ -f "$real/demo.jpg" ]; then
  args+=(--image "$real/demo.jpg" --mask "$real/demo_seg.png")
else
  echo "train-tool-model: $real absent: training on the simulator only" >&2
fi
mkdir -p "$(dirname "$out")"
"$bin" train-tool-model "${args[@]}" --out "$out"
