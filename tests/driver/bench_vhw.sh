#!/bin/sh
# Capture -> page-flip latency (kernel timestamps: the V4L2 buffer's, the flip
# event's) and CPU per frame of `endotower run` on the vhw board, in the qemu guest.
# Twice: bgrx (vivid's DMABUF scanned out by vkms, no copy) and yuyv (one CPU
# conversion per frame, vkms has no YUV plane). Figures for docs/performance.md.
# Usage (host): tests/driver/run-in-guest.sh --modules "vivid:n_devs=1 vkms:enable_overlay=1 gpio-sim" \
#                 -- tests/driver/bench_vhw.sh build/release [SECONDS]
set -u
build=$1 seconds=${2:-30}
here=$(cd "$(dirname "$0")" && pwd)
cfg=/sys/kernel/config/gpio-sim/endotower
mkdir -p $cfg/gpio-bank0 && echo 4 >$cfg/gpio-bank0/num_lines && echo endotower-button >$cfg/gpio-bank0/label && echo 1 >$cfg/live
for fmt in bgrx yuyv; do
    sed "s/^  format: bgrx .*/  format: $fmt/" "$here/../../board/vhw/board.yaml" >/tmp/vhw-$fmt.yaml
    # The board's relative calibration path: not used by run.
    echo "== capture format $fmt, $seconds s"
    "$build/firmware/endotower" run --board /tmp/vhw-$fmt.yaml --seconds "$seconds" 2>&1 |
        grep -v -e MESA -e kmsro -e 'failed to load driver' -e 'handle not connected'
done
