#!/usr/bin/env bash
# Trains the shipped tool-gesture model (board/sim/models/gestures.yml) from the
# random-pose training scenarios (board/sim/scenarios/gestures/train_*.yaml, written
# by toolchain/gen-gesture-scenarios.py) rendered at seed 9006, a seed no test suite
# uses; with the profile (default: the shipped model), topology or extended features
# two networks, the single-tool one also trained on single_*.yaml (the SCI's
# activation pose; docs/gestures.md, "Two networks"), and with the profile features
# the single-tool and profile networks on more_single_*.yaml too (three times the
# random single-tool poses; "Profile"), rendered over four tissues (seeds 9006-9009;
# "More tissues"); with the profile features a second stage then
# trains the two-tool network alone, by RPROP, on crossings from every side
# (varied_double_*.yaml; "Crossings from every side"), over two tissues (seeds 9006
# and 9007). The fig322/fig323/fig312 suites at their own seeds and test_* are the
# held-out test sets (docs/gestures.md).
# Deterministic: same bytes every run.
# Usage: toolchain/train-gesture-model.sh [OUT] [--features book|extended|topology|profile]
#        [--segmentation likelihood|morphology] [--threshold N] [--single-threshold M]
#        [--test DIR]...
#        (default: the shipped model)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$root/board/sim/models/gestures.yml}
shift || true
# The shipped model's features unless the caller names others.
case " $* " in
  *" --features "*) ;;
  *) set -- --features profile "$@" ;;
esac
# The shipped model's mask threshold (likelihood segmentation; stored in the model)
# unless the caller names one: 170, where 128 (even odds) let the wet tissue's sheen
# join the jaws (docs/gestures.md, "The mask threshold").
case " $* " in
  *" --threshold "* | *" morphology "*) ;;
  *) set -- --threshold 170 "$@" ;;
esac
# And the one-tool mask's (a region entering once is measured on the mask at 190,
# which joins less sheen to a lone tool's jaws; crossings stay at 170: docs/gestures.md,
# "Two masks"); --single-threshold 0 for one mask, as the models before 2026-11-30.
case " $* " in
  *" --single-threshold "* | *" morphology "*) ;;
  *) set -- --single-threshold 190 "$@" ;;
esac
bin=$root/build/release/firmware/endotower
[ -x "$bin" ] || "$root/toolchain/build.sh" release
work=$root/build/gesture-train
mkdir -p "$work"
# Renders scenario F at SEED into $work/NAME unless it is there already.
render() {
  [ -f "$work/$3/truth.jsonl" ] || "$bin" scene --scenario "$1" --seed "$2" --size 640x480 --out "$work/$3" >/dev/null
}
args=()
for f in "$root"/board/sim/scenarios/gestures/train_*.yaml; do
  s=$(basename "$f" .yaml)
  render "$f" 9006 "$s"
  args+=(--scene "$work/$s")
done
case " $* " in
  *" book "*) ;;  # the book's baseline: one 6-20-7 network
  *)
    args+=(--networks two)
    for f in "$root"/board/sim/scenarios/gestures/single_*.yaml; do
      s=$(basename "$f" .yaml)
      render "$f" 9006 "$s"
      args+=(--single-tool-scene "$work/$s")
    done
    case " $* " in
      *" profile "*)
        for f in "$root"/board/sim/scenarios/gestures/more_single_*.yaml; do
          s=$(basename "$f" .yaml)
          render "$f" 9006 "$s"
          args+=(--single-tool-scene "$work/$s")
        done
        # The same poses over three more tissues (the scene seed draws the tissue):
        # glints lie elsewhere beside the shafts, so the networks do not learn one
        # tissue's glints as part of the jaws (docs/gestures.md, "More tissues").
        for seed in 9007 9008 9009; do
          for f in "$root"/board/sim/scenarios/gestures/more_single_*.yaml; do
            s=s${seed}_$(basename "$f" .yaml)
            render "$f" "$seed" "$s"
            args+=(--single-tool-scene "$work/$s")
          done
        done
        ;;
    esac
    ;;
esac
mkdir -p "$(dirname "$out")"
tool_model=$root/board/sim/models/gesture_tool_likelihood.bin  # toolchain/train-tool-model.sh --gestures
# Stage 1: every network, training regions labelled by the fixed match distance
# (--match-widths 0), as the models before 2026-11-27 (evening) were trained.
case " $* " in
  *" profile "*) first=$(mktemp "${TMPDIR:-/tmp}/gestures-stage1.XXXXXX") ;;
  *) first=$out ;;
esac
"$bin" train-gestures "${args[@]}" --match-widths 0 --tool-model "$tool_model" --out "$first" "$@"
case " $* " in
  *" profile "*)
    # Stage 2 (the shipped profile model): the two-tool network trained anew on the
    # crossings from incisions on every side, with 5 and 10 mm graspers (varied_double_*),
    # three times fig. 3.23's random crossings (more_double_*) and the activation pose's
    # scissors and graspers (single_activation_*: one tool that enters twice is not a
    # two-tool gesture); the single-tool and profile networks stay stage 1's
    # (docs/gestures.md, "Crossings from every side").
    two=()
    for f in "$root"/board/sim/scenarios/gestures/varied_double_*.yaml "$root"/board/sim/scenarios/gestures/more_double_*.yaml; do
      s=$(basename "$f" .yaml)
      render "$f" 9006 "$s"
      two+=(--two-tool-scene "$work/$s")
    done
    # The same crossings over a second tissue (seed 9007; docs/gestures.md, "More tissues").
    for f in "$root"/board/sim/scenarios/gestures/more_double_*.yaml "$root"/board/sim/scenarios/gestures/varied_double_*.yaml; do
      s=s9007_$(basename "$f" .yaml)
      render "$f" 9007 "$s"
      two+=(--two-tool-scene "$work/$s")
    done
    two+=(--two-tool-scene "$work/single_activation_scissors" --two-tool-scene "$work/single_activation_grasper")
    scenes=()
    for f in "$root"/board/sim/scenarios/gestures/train_*.yaml; do scenes+=(--scene "$work/$(basename "$f" .yaml)"); done
    "$bin" train-gestures --two-tool-only-from "$first" --rprop "${scenes[@]}" "${two[@]}" \
      --tool-model "$tool_model" --out "$out" "$@"
    rm -f "$first"
    ;;
esac
