#!/bin/bash
# Tables 6.5/6.6 layout for docs/regions.md: renders the t65 emulated suites and the
# t66 in-vivo-like ones (scene simulator, exact truth), tracks the truth's first-frame region with each descriptor through
# `endotower sim --region`, and scores it with `endotower eval`.
# usage: toolchain/region-suites.sh [OUT_DIR] [SIZE]   (SIZE 640x480 default, or 1920x1080)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bin=${ENDOTOWER:-$root/build/release/firmware/endotower}
out=${1:-$root/out/regions}
size=${2:-640x480}
mkdir -p "$out"
printf '| Group | change | SIFT | ORB | AKAZE |\n|---|---|---|---|---|\n'
for name in t65_emulated_1 t65_emulated_2 t65_emulated_3 t65_emulated_4 t65_emulated_5 t65_emulated_6 \
    t66_deformation t66_occlusion t66_viewpoint; do
    scene=$out/${name}_$size
    [ -d "$scene" ] || "$bin" scene --scenario "$root/board/sim/scenarios/$name.yaml" --size "$size" --out "$scene" >/dev/null
    region=$(head -1 "$scene/truth.jsonl" | python3 -c 'import json,sys; print(" ".join("%.3f,%.3f" % tuple(p) for p in json.load(sys.stdin)["regions"][0]["polygon_px"]))')
    change=$(tail -1 "$scene/truth.jsonl" | python3 -c 'import json,sys; print(json.load(sys.stdin)["regions"][0]["change"])')
    row="| $name | $change |"
    for d in sift orb akaze; do
        printf 'board: regions\nanalysis:\n  stage: none\n  tracker: none\n  regions: {descriptor: %s}\n' "$d" > "$out/board_$d.yaml"
        "$bin" sim --board "$out/board_$d.yaml" --input "$scene/frames" --out "$out/o.avi" \
            --trace "$scene/trace_$d.jsonl" --region "$region" >/dev/null 2>&1 || true
        s=$("$bin" eval --trace "$scene/trace_$d.jsonl" --truth "$scene/truth.jsonl" | grep '^regions:' || echo 'regions: failed')
        # "regions: 24 region-frames: GOOD 24, OK 0, FAIL 0; mean corner error 0.16 px";
        # a region that cannot be marked (too few features) has no regions member at all.
        row="$row $(echo "$s" | sed -E -e 's/.*GOOD ([0-9]+), OK ([0-9]+), FAIL ([0-9]+); mean corner error ([0-9.]+) px.*/GOOD \1, OK \2, FAIL \3; \4 px/' -e 's/regions: failed/not marked/') |"
    done
    echo "$row"
done
