#!/usr/bin/env bash
# clang-tidy (config: .clang-tidy) over the project's own sources, using the release
# build's compile_commands.json. Any warning fails (WarningsAsErrors).
#   ./toolchain/tidy.sh            # every source
#   ./toolchain/tidy.sh FILE...    # just these
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
db=build/release
if [ ! -f "$db/compile_commands.json" ]; then
  cmake --preset release -DCMAKE_EXPORT_COMPILE_COMMANDS=ON >/dev/null
fi
if [ $# -gt 0 ]; then
  files=("$@")
else
  # The project's own translation units (not build/, not third-party).
  mapfile -t files < <(git ls-files 'app/*.cpp' 'drivers/*.cpp' 'firmware/*.cpp' 'hal/*.cpp' 'tests/*.cpp')
fi
log=$(mktemp)
trap 'rm -f "$log"' EXIT
status=0
run-clang-tidy -quiet -p "$db" -j "$(nproc)" "${files[@]/#/$root/}" >"$log" 2>&1 || status=$?
# Only the findings (no colour codes, no per-file chatter).
sed 's/\x1b\[[0-9;]*m//g' "$log" |
  grep -v -E "^([0-9]+ warnings? generated|Suppressed [0-9]+ warnings|Use -header-filter|clang-tidy-[0-9]+ |Running clang-tidy)" || true
if grep -q -E "(warning|error): " "$log"; then status=1; fi
exit "$status"
