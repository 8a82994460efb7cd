#!/usr/bin/env bash
# Checks run-in-guest.sh itself in one boot: the command runs as root in the guest
# kernel with the requested module loaded, its exit status, stdout and stderr come
# back, a --share directory is writable, and the host root is read-only underneath
# the guest's overlay (writes stay in the guest).
set -uo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
cache=${1:-}
share=$(mktemp -d) || exit 1
trap 'rm -rf "$share" "$out" "$err"' EXIT
out=$(mktemp) err=$(mktemp)
marker=$share/../endotower-harness-$$.overlay
"$here/run-in-guest.sh" ${cache:+--cache "$cache"} --modules "uhid" --share "$share" -- \
    sh -c 'echo "uid=$(id -u) kernel=$(uname -r) guest=$ENDOTOWER_IN_GUEST"; test -c /dev/uhid && echo uhid-ok;
           echo to-stderr >&2; echo shared >"$1/file"; echo x >"$2"; exit 7' sh "$share" "$marker" >"$out" 2>"$err"
rc=$?
fail() { echo "harness_test: FAIL: $*"; echo "--- stdout"; cat "$out"; echo "--- stderr"; cat "$err"; exit 1; }
[ $rc -eq 77 ] && { cat "$err"; exit 77; }
[ $rc -eq 7 ] || fail "exit status $rc, expected 7"
grep -q '^uid=0 kernel=6\.1\.0-.*-amd64 guest=1$' "$out" || fail "stdout lacks root/guest kernel line"
grep -q '^uhid-ok$' "$out" || fail "/dev/uhid missing with --modules uhid"
grep -q '^to-stderr$' "$err" || fail "stderr did not come back"
[ "$(cat "$share/file" 2>/dev/null)" = shared ] || fail "--share directory not written"
[ ! -e "$marker" ] || { rm -f "$marker"; fail "a write outside --share reached the host"; }
echo "harness_test: PASS"
