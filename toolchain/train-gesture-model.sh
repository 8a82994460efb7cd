#!/usr/bin/env bash
# Trains the shipped tool-gesture model (board/sim/models/gestures.yml) from the
# random-pose training scenarios (board/sim/scenarios/gestures/train_*.yaml, written
# by toolchain/gen-gesture-scenarios.py) rendered at seed 9006, a seed no test suite
# uses; with the profile (default: the shipped model), topology or extended features
# two networks, the single-tool one also trained on single_*.yaml (the SCI's
# activation pose; docs/gestures.md, "Two networks"), and with the profile features
# the single-tool and profile networks on more_single_*.yaml too (three times the
# random single-tool poses; "Profile"). The fig322/fig323/fig312 suites at their own seeds and
# test_random* are the held-out test sets (docs/gestures.md). Deterministic: same
# bytes every run.
# Usage: toolchain/train-gesture-model.sh [OUT] [--features book|extended|topology|profile]
#        [--segmentation likelihood|morphology] [--test DIR]...  (default: the shipped model)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$root/board/sim/models/gestures.yml}
shift || true
# The shipped model's features unless the caller names others.
case " $* " in
  *" --features "*) ;;
  *) set -- --features profile "$@" ;;
esac
bin=$root/build/release/firmware/endotower
[ -x "$bin" ] || "$root/toolchain/build.sh" release
work=$root/build/gesture-train
mkdir -p "$work"
args=()
for f in "$root"/board/sim/scenarios/gestures/train_*.yaml; do
  s=$(basename "$f" .yaml)
  [ -f "$work/$s/truth.jsonl" ] || "$bin" scene --scenario "$f" --seed 9006 --size 640x480 --out "$work/$s" >/dev/null
  args+=(--scene "$work/$s")
done
case " $* " in
  *" book "*) ;;  # the book's baseline: one 6-20-7 network
  *)
    args+=(--networks two)
    for f in "$root"/board/sim/scenarios/gestures/single_*.yaml; do
      s=$(basename "$f" .yaml)
      [ -f "$work/$s/truth.jsonl" ] || "$bin" scene --scenario "$f" --seed 9006 --size 640x480 --out "$work/$s" >/dev/null
      args+=(--single-tool-scene "$work/$s")
    done
    case " $* " in
      *" profile "*)
        for f in "$root"/board/sim/scenarios/gestures/more_single_*.yaml; do
          s=$(basename "$f" .yaml)
          [ -f "$work/$s/truth.jsonl" ] || "$bin" scene --scenario "$f" --seed 9006 --size 640x480 --out "$work/$s" >/dev/null
          args+=(--single-tool-scene "$work/$s")
        done
        ;;
    esac
    ;;
esac
mkdir -p "$(dirname "$out")"
"$bin" train-gestures "${args[@]}" --tool-model "$root/board/sim/models/tool_likelihood.bin" --out "$out" "$@"
