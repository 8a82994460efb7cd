#!/usr/bin/env bash
# Builds the libFuzzer targets (preset "fuzz", clang) and runs each for SECONDS
# (default 60) on a copy of its committed corpus. A crash stops with its input saved
# as build/fuzz/crash-*; add it to tests/fuzz/corpus/NAME and fix the parser.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
seconds=${1:-60}
"$root/toolchain/install-deps.sh"
cd "$root"
cmake --preset fuzz >/dev/null
cmake --build --preset fuzz -j "$(nproc)"
for t in timeline trace_line board hid_report; do
  work="build/fuzz/corpus-$t"
  rm -rf "$work" && mkdir -p "$work" && cp tests/fuzz/corpus/$t/* "$work/"
  echo "fuzz_$t: ${seconds} s"
  "build/fuzz/tests/fuzz/fuzz_$t" -max_total_time="$seconds" -max_len=4096 \
    -artifact_prefix="build/fuzz/" -print_final_stats=1 "$work" 2>&1 | grep -E "^(stat::number_of_executed_units|Done|==.*ERROR|SUMMARY)" || true
  test "${PIPESTATUS[0]}" -eq 0
done
