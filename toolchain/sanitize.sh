#!/usr/bin/env bash
# Builds one sanitizer preset and runs tests under it (issue 10): ASan + UBSan the whole
# suite, TSan the multi-threaded test programs (CI) or the whole suite.
#   ./toolchain/sanitize.sh asan       # AddressSanitizer + UndefinedBehaviorSanitizer
#   ./toolchain/sanitize.sh tsan       # ThreadSanitizer, the multi-threaded programs (CI)
#   ./toolchain/sanitize.sh tsan-all   # ThreadSanitizer, the whole suite (31 min of tests
#                                      # on 2 cores plus the build: not in CI)
# Any report fails the run: ASan/UBSan abort on the first error (the preset builds
# with -fno-sanitize-recover=undefined), TSan exits non-zero (halt_on_error).
# The qemu tests (label "driver") are left out: the guest boots a kernel of its own and
# runs the release binaries; their code is the same code the unit tests cover here.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
mode=${1:?usage: sanitize.sh asan|tsan|tsan-all}
case "$mode" in asan | tsan | tsan-all) ;; *) echo "sanitize.sh: unknown mode '$mode' (asan, tsan or tsan-all)" >&2; exit 2 ;; esac
preset=${mode%-all}
"$root/toolchain/install-deps.sh"
cd "$root"
cmake --preset "$preset" >/dev/null
# Leak detection is off: Mesa's software GL driver (swrast_dri.so, loaded by the
# overlay renderer and the display tests) leaves its screen allocated at exit and is
# dlclosed before LeakSanitizer looks, so its frames are unattributable and cannot be
# suppressed by module. Every other ASan/UBSan check stays on for the whole suite.
export ASAN_OPTIONS="detect_leaks=0:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1"
if [ "$mode" != tsan ]; then
  cmake --build --preset "$preset" -j "$(nproc)"
  # Sanitized code runs 2-15x slower: scale the per-test timeout, not the assertions.
  # Under TSan also the replay's wall-clock watchdog on a stage call (2 s; one region
  # detection on a 1080p frame takes longer there), as under qemu (cross-test.sh).
  if [ "$mode" = tsan-all ]; then export ENDOTOWER_REPLAY_WATCHDOG_MS=${ENDOTOWER_REPLAY_WATCHDOG_MS:-60000}; fi
  ctest --preset "$preset" -j "$(nproc)" -LE driver --timeout 1500
else
  # TSan: the test programs whose code runs on several threads (the pipeline's video
  # and analysis threads, capture and input sources, the fault matrix). The whole
  # suite under TSan (tsan-all) is not part of CI: 31 min of tests on two cores plus a
  # cold build (docs/reliability.md).
  # Also the undistorter's helper thread (set_threads(2)): its tests only, the rest of
  # test_calibration is single-threaded fitting.
  targets=(test_app test_sim test_reliability test_calibration)
  declare -A filter=([test_calibration]='Undistorter.*')
  cmake --build --preset "$preset" -j "$(nproc)" --target "${targets[@]}"
  for t in "${targets[@]}"; do
    exe=$(find "build/$preset/tests" -type f -name "$t" -perm -u+x | head -1)
    [ -n "$exe" ] || { echo "sanitize.sh: $t was not built" >&2; exit 1; }
    (cd "$(dirname "$exe")" && "./$t" --gtest_brief=1 --gtest_filter="${filter[$t]:-*}")
  done
fi
