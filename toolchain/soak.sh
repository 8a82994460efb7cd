#!/usr/bin/env bash
# Soak (issue 10; not in CI): a deterministic 1080p60 replay of MINUTES of video
# (default 60) on the virtual clock, with the sim board's analysis (likelihood tool
# tracking, gestures) and a tracked region, writing only the trace. Samples the
# process's resident memory, open file descriptors and threads every 5 s into
# build/soak/samples.csv, then checks the trace: every frame at the fixed latency,
# none late, and no growth of descriptors or threads (the second half of the run needs
# no more than the quarter after warm-up). Prints the summary docs/reliability.md records.
#   ./toolchain/soak.sh [MINUTES] [INPUT]
# INPUT: a 1080p video, looped (default ../shared/data/endovis17_demo/short_source.mp4,
# 20 frames of a real da Vinci scene at 1920x1080, replayed at 60 fps).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
minutes=${1:-60}
input=${2:-$root/../shared/data/endovis17_demo/short_source.mp4}
[ -f "$input" ] || { echo "soak.sh: no input video $input" >&2; exit 2; }
cd "$root"
cmake --preset release >/dev/null
cmake --build build/release --target endotower -j "$(nproc)" >/dev/null
bin=build/release/firmware/endotower
out=build/soak
rm -rf "$out" && mkdir -p "$out" && : >"$out/events.txt"
# The sim board at 60 fps (sim.fps), its models and SCI media by absolute path.
sed -e "s|models/|$root/board/sim/models/|" -e "s|sci_media|$root/board/sim/sci_media|g" -e "s|^  realtime: .*|&\n  fps: 60|" board/sim/board.yaml >"$out/board.yaml"

# Frames in one pass of the input (the trace of a one-pass run has one line per frame).
"$bin" sim --board "$out/board.yaml" --input "$input" --events "$out/events.txt" --out "" \
  --frames "$out/pass" --trace "$out/pass.jsonl" >/dev/null
per_pass=$(wc -l <"$out/pass.jsonl")
rm -rf "$out/pass"
loops=$(( (minutes * 60 * 60 + per_pass - 1) / per_pass ))
echo "soak: $minutes min of 1080p60 = $loops passes of $per_pass frames of $input"

start=$(date +%s)
"$bin" sim --board "$out/board.yaml" --input "$input" --events "$out/events.txt" --out "" --loop "$loops" \
  --region "800,400 1100,400 1100,650 800,650" --trace "$out/trace.jsonl" >"$out/sim.txt" 2>&1 &
pid=$!
echo "wall_s,video_frames,rss_kb,fds,threads" >"$out/samples.csv"
while kill -0 "$pid" 2>/dev/null; do
  rss=$(awk '/^VmRSS/ {print $2}' "/proc/$pid/status" 2>/dev/null || true)
  thr=$(awk '/^Threads/ {print $2}' "/proc/$pid/status" 2>/dev/null || true)
  fds=$(ls "/proc/$pid/fd" 2>/dev/null | wc -l)
  frames=$( (cat "$out/trace.jsonl.tmp" 2>/dev/null || true) | wc -l)
  [ -n "$rss" ] && echo "$(( $(date +%s) - start )),$frames,$rss,$fds,$thr" >>"$out/samples.csv"
  sleep 5
done
wait "$pid"
tail -n 12 "$out/sim.txt"
python3 - "$out" <<'PY'
import csv, json, sys
out = sys.argv[1]
s = list(csv.DictReader(open(f"{out}/samples.csv")))
lat, late, n = set(), 0, 0
for line in open(f"{out}/trace.jsonl"):
    r = json.loads(line)
    n += 1
    lat.add(r["latency_ns"])
    late += r["late"]
warm = [x for x in s if int(x["video_frames"]) >= n // 4] or s  # warm-up: the first quarter
rss = [int(x["rss_kb"]) for x in warm]
print(f"frames {n} ({n / 3600:.1f} video min at 60 fps), latencies {sorted(lat)} ns, late {late}")
print(f"RSS after warm-up: first {rss[0]} kB, min {min(rss)}, max {max(rss)}, last {rss[-1]} kB")
from collections import Counter
def seen(key, rows):
    return ", ".join(f"{k}: {v}" for k, v in sorted(Counter(int(x[key]) for x in rows).items()))
print(f"after warm-up: fds {{{seen('fds', warm)}}} samples, threads {{{seen('threads', warm)}}} samples")
print(f"wall {s[-1]['wall_s'] if s else 0} s; samples: {out}/samples.csv")
# Growth: the second half of the run may not need more descriptors or threads than the
# quarter after warm-up (the recording's decoder is reopened every pass, so its threads
# come and go; a leak only ever adds).
half = [x for x in s if int(x["video_frames"]) >= n // 2] or warm
early = [x for x in warm if int(x["video_frames"]) < n // 2] or warm
grew = any(max(int(x[k]) for x in half) > max(int(x[k]) for x in early) for k in ("fds", "threads"))
ok = late == 0 and len(lat) == 1 and not grew
print("soak: " + ("pass" if ok else "FAIL") + f" (late {late}, latencies {len(lat)}, fds/threads grew: {grew})")
sys.exit(0 if ok else 1)
PY
