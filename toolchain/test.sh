#!/usr/bin/env bash
# README command 2: set up if needed, build and run the whole test suite with CTest.
# Optional argument: the preset (release, debug, asan, tsan).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
preset=${1:-release}
"$root/toolchain/build.sh" "$preset"
cd "$root"
ctest --preset "$preset" -j "$(nproc)"
