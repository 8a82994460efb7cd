#!/usr/bin/env bash
# Builds one sanitizer preset and runs the whole test suite under it (issue 10).
#   ./toolchain/sanitize.sh asan   # AddressSanitizer + UndefinedBehaviorSanitizer
#   ./toolchain/sanitize.sh tsan   # ThreadSanitizer
# Any report fails the run: ASan/UBSan abort on the first error (the preset builds
# with -fno-sanitize-recover=undefined), TSan exits non-zero (halt_on_error).
# The qemu tests (label "driver") are left out: the guest boots a kernel of its own and
# runs the release binaries; their code is the same code the unit tests cover here.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
preset=${1:?usage: sanitize.sh asan|tsan}
case "$preset" in asan | tsan) ;; *) echo "sanitize.sh: unknown preset '$preset' (asan or tsan)" >&2; exit 2 ;; esac
"$root/toolchain/install-deps.sh"
cd "$root"
cmake --preset "$preset" >/dev/null
cmake --build --preset "$preset" -j "$(nproc)"
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1"
# Sanitized code runs 2-15x slower: scale the per-test timeout, not the assertions.
ctest --preset "$preset" -j "$(nproc)" -LE driver --timeout 1500
