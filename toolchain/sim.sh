#!/usr/bin/env bash
# README command 1: set up if needed, build (Release) and run the appliance in
# simulation on the bundled recording. Extra arguments go to `endotower sim`.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/toolchain/build.sh" release
exec "$root/build/release/firmware/endotower" sim --board "$root/board/sim/board.yaml" "$@"
