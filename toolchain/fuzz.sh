#!/usr/bin/env bash
# Builds the libFuzzer targets (preset "fuzz", clang) and runs each for SECONDS
# (default 60) on a copy of its committed corpus. A crash stops with its input saved
# as build/fuzz/crash-*; add it to tests/fuzz/corpus/NAME and fix the parser. One input
# running past 20 s fails the same way (build/fuzz/timeout-*): a hang must not eat CI's
# time (a gesture model without weights and with a huge hidden layer once ran for half an hour).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
seconds=${1:-60}
"$root/toolchain/install-deps.sh"
cd "$root"
cmake --preset fuzz >/dev/null
cmake --build --preset fuzz -j "$(nproc)"
# One target per core at a time (each target is one process), corpus folder NAME for
# target fuzz_NAME; its log in build/fuzz/NAME.log.
fuzz_one() {
  local t=$1 work="build/fuzz/corpus-$1" log="build/fuzz/$1.log" status=0
  rm -rf "$work" && mkdir -p "$work" && cp tests/fuzz/corpus/$t/* "$work/"
  "build/fuzz/tests/fuzz/fuzz_$t" -max_total_time="$seconds" -timeout=20 -max_len=70000 \
    -artifact_prefix="build/fuzz/" -print_final_stats=1 "$work" >"$log" 2>&1 || status=$?
  echo "fuzz_$t: ${seconds} s, exit $status"
  grep -E "^(stat::number_of_executed_units|Done|==.*ERROR|SUMMARY)" "$log" || true
  return "$status"
}
# xargs runs them and exits non-zero when any of them did.
export -f fuzz_one
export seconds
ls tests/fuzz/corpus | xargs -P "${JOBS:-$(nproc)}" -I{} bash -c 'fuzz_one "$1"' _ {}
