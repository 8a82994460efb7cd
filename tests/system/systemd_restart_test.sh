#!/usr/bin/env bash
# The shipped unit (board/common/endotower.service) under a real systemd: the service is
# SIGKILLed three times and must be running again within 2 s each time (issue 10;
# RestartSec=1s, StartLimitIntervalSec=0 so it never gives up).
#
# systemd runs as PID 1 of a private PID and mount namespace on this machine (root and
# unshare needed): /run, /etc/systemd/system, /var/lib and /var/log are tmpfs there,
# and /etc/passwd and /etc/group are copies with the unit's 'endotower' user added, so
# nothing of the host changes. The unit is installed as shipped, hardening included;
# a drop-in only replaces ExecStart: the sim board's recording replayed on the real
# clock (`endotower sim --realtime`), since there is no camera here.
#
# Usage: systemd_restart_test.sh ENDOTOWER_BINARY REPO_DIR WORK_DIR
# Exit: 0 pass, 1 fail, 77 skipped (not root, no unshare or systemd, or systemd does not
# come up in a namespace here: the reason is printed).
set -uo pipefail
bin=$(realpath "$1") repo=$(realpath "$2") work=$3
skip() { echo "SKIP: $*"; exit 77; }
fail() { echo "FAIL: $*"; exit 1; }
[ "$(id -u)" = 0 ] || skip "needs root (systemd as PID 1 of a private namespace)"
sd=/lib/systemd/systemd
[ -x "$sd" ] || skip "no $sd"
command -v unshare >/dev/null || skip "no unshare"
unshare --pid --fork --mount --mount-proc true 2>/dev/null || skip "cannot create a PID and mount namespace"
getent passwd endotower >/dev/null && skip "an 'endotower' user exists on this host already"

rm -rf "$work" && mkdir -p "$work" && work=$(realpath "$work")
chmod 0755 "$work"
result=$work/result

# Inside the namespace, as root, before systemd: private copies of what it changes.
cat >"$work/boot.sh" <<EOF
#!/bin/bash
set -e
mount --make-rprivate /
for d in /run /etc/systemd/system /var/lib /var/log; do mount -t tmpfs -o mode=0755 tmpfs "\$d"; done
for d in /tmp /var/tmp; do mount -t tmpfs -o mode=1777 tmpfs "\$d"; done
cp /etc/machine-id "$work/machine-id" && mount --bind "$work/machine-id" /etc/machine-id
cp /etc/passwd "$work/passwd" && cp /etc/group "$work/group"
echo 'endotower:x:64990:64990:endotower video appliance:/var/lib/endotower:/usr/sbin/nologin' >>"$work/passwd"
echo 'endotower:x:64990:' >>"$work/group"
mount --bind "$work/passwd" /etc/passwd && mount --bind "$work/group" /etc/group
u=/etc/systemd/system
# Only the test's units start (no sysinit.target); the early-boot units that write to
# the shared file system, devices or kernel settings are masked besides.
for m in systemd-tmpfiles-setup systemd-tmpfiles-setup-dev systemd-tmpfiles-setup-dev-early \\
         systemd-tmpfiles-clean systemd-udevd systemd-udev-trigger systemd-udev-settle \\
         systemd-sysctl systemd-modules-load ldconfig systemd-sysusers systemd-hwdb-update \\
         systemd-binfmt systemd-firstboot systemd-machine-id-commit systemd-remount-fs \\
         systemd-journal-catalog-update kmod-static-nodes; do
    ln -s /dev/null \$u/\$m.service
done
ln -s /dev/null \$u/systemd-tmpfiles-clean.timer
cp "$repo/board/common/endotower.service" \$u/endotower.service
mkdir -p \$u/endotower.service.d
printf '%s\n' '[Unit]' 'DefaultDependencies=no' '[Service]' 'ExecStart=' \\
  'ExecStart=$bin sim --board $repo/board/sim/board.yaml --realtime --loop 100000 --out "" --trace trace.jsonl' \\
  >\$u/endotower.service.d/test.conf
printf '%s\n' '[Unit]' 'DefaultDependencies=no' 'After=endotower.service' '[Service]' 'Type=oneshot' \\
  'ExecStart=$work/check.sh' >\$u/restart-check.service
printf '%s\n' '[Unit]' 'DefaultDependencies=no' 'Wants=endotower.service restart-check.service' >\$u/restart-test.target
export container=other
exec $sd --system --unit=restart-test.target --log-target=console --show-status=no
EOF

# Inside, as a oneshot unit once the service has started: kill it, time the restart.
cat >"$work/check.sh" <<EOF
#!/bin/bash
main_pid() { systemctl show -P MainPID endotower.service; }
now_ms() { echo \$((\$(date +%s%N) / 1000000)); }
mono_us() { python3 -c 'import time; print(time.monotonic_ns() // 1000)'; }
out=$result.tmp
: >"\$out"
for i in \$(seq 200); do
    pid=\$(main_pid)
    [ "\$pid" -gt 0 ] && systemctl -q is-active endotower.service && break
    sleep 0.05
done
[ "\$pid" -gt 0 ] || { echo "never started: \$(systemctl status endotower.service 2>&1 | tail -5)" >>"\$out"; mv "\$out" $result; exit 0; }
# MainPID is known (and the unit "active") from the fork on; the child drops to the
# unit's user while it sets up the sandbox, just before exec. Read the user once it has
# exec'd the binary, not in between (a slow machine saw "root" there).
for i in \$(seq 200); do
    [ "\$(cat /proc/\$pid/comm 2>/dev/null)" = endotower ] && break
    sleep 0.05
done
echo "user \$(ps -o user= -p \$pid) \$(cat /proc/\$pid/comm 2>/dev/null)" >>"\$out"
for round in 1 2 3; do
    sleep 2  # serving: the process stays up
    kill -0 "\$pid" 2>/dev/null || { echo "died on its own: \$(systemctl status endotower.service 2>&1 | tail -5)" >>"\$out"; break; }
    t0=\$(now_ms)
    m0=\$(mono_us)
    kill -9 "\$pid"
    new=0
    while [ \$((\$(now_ms) - t0)) -lt 10000 ]; do
        new=\$(main_pid)
        [ "\$new" -gt 0 ] && [ "\$new" != "\$pid" ] && systemctl -q is-active endotower.service && break
        new=0
        sleep 0.01
    done
    polled=\$((\$(now_ms) - t0))
    # systemd's own record: the new process's start on the monotonic clock.
    started=\$(systemctl show -P ExecMainStartTimestampMonotonic endotower.service)
    echo "restart \$round \$new \$(((started - m0) / 1000)) \$polled" >>"\$out"
    [ "\$new" -gt 0 ] || break
    pid=\$new
done
echo "nrestarts \$(systemctl show -P NRestarts endotower.service)" >>"\$out"
mv "\$out" $result
EOF
chmod +x "$work/boot.sh" "$work/check.sh"

setsid unshare --pid --fork --mount --mount-proc "$work/boot.sh" >"$work/systemd.log" 2>&1 </dev/null &
ns=$!
stop() {
    # SIGKILL to the namespace's PID 1 ends everything in it.
    pkill -9 -P "$ns" 2>/dev/null
    kill -9 "$ns" 2>/dev/null
    wait "$ns" 2>/dev/null
}
trap stop EXIT
for _ in $(seq 600); do
    [ -f "$result" ] && break
    kill -0 "$ns" 2>/dev/null || break
    sleep 0.1
done
stop
trap - EXIT
if [ ! -f "$result" ]; then
    # The check unit runs whether or not the service starts, so no result means that
    # systemd itself did not come up in a namespace on this machine.
    tail -20 "$work/systemd.log"
    skip "systemd did not run the test's units within 60 s here (its log above)"
fi
cat "$result"
grep -q '^user endotower endotower$' "$result" || fail "the service did not run as the unprivileged user 'endotower'"
status=0
for round in 1 2 3; do
    line=$(grep "^restart $round " "$result") || { echo "FAIL: restart $round missing"; status=1; continue; }
    read -r _ _ pid ms polled <<<"$line"
    [ "$pid" -gt 0 ] || { echo "FAIL: not restarted within 10 s (round $round)"; status=1; continue; }
    # From the SIGKILL to systemd starting the new process (its own timestamp, not our
    # polling, which is printed beside it): RestartSec=1s, so not before 1 s, and
    # within 2 s (the issue's bound; the rest is systemd noticing and forking).
    echo "round $round: restarted $ms ms after the SIGKILL (seen active after $polled ms)"
    if [ "$ms" -lt 1000 ] || [ "$ms" -gt 2000 ]; then
        echo "FAIL: round $round restarted after $ms ms, expected 1000..2000"
        status=1
    fi
done
grep -q '^nrestarts 3$' "$result" || { echo "FAIL: systemd counted $(grep nrestarts "$result") restarts, expected 3"; status=1; }
[ $status = 0 ] && echo "PASS: restarted 3 times, each within 2 s of the SIGKILL"
exit $status
