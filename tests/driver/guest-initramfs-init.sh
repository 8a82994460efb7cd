#!/bin/busybox sh
# PID 1 of the driver-test guest (inside the busybox initramfs built by setup.sh).
# Loads virtio + 9p + overlay, mounts the host root (9p tag hostroot, read-only)
# under a tmpfs overlay, mounts the results share (tag results) at the host path
# named in its `path` file, and switch_roots into RESULTS/guest.sh (written by
# run-in-guest.sh), which runs the test command and powers off.
/bin/busybox mkdir -p /usr/bin /usr/sbin /sbin
/bin/busybox --install -s
mount -t proc proc /proc
mount -t sysfs sysfs /sys
mount -t devtmpfs devtmpfs /dev
fail() { echo "guest-init: $*" >/dev/console; poweroff -f; }
while read -r m; do
    insmod "/modules/$m.ko" 2>/dev/null || [ -d "/sys/module/$m" ] || echo "guest-init: insmod $m failed"
done </modules/order
mount -t 9p -o trans=virtio,version=9p2000.L,ro,msize=512000,cache=loose hostroot /lower || fail "mount hostroot"
mount -t tmpfs -o mode=0755 tmpfs /rw || fail "mount tmpfs"
mkdir -p /rw/upper /rw/work
mount -t overlay -o lowerdir=/lower,upperdir=/rw/upper,workdir=/rw/work overlay /newroot || fail "mount overlay"
mount -t 9p -o trans=virtio,version=9p2000.L,msize=512000 results /results || fail "mount results"
rpath=$(cat /results/path) || fail "no results/path"
mkdir -p "/newroot$rpath"
mount --move /results "/newroot$rpath" || fail "move results"
for s in $(cat "/newroot$rpath/shares" 2>/dev/null); do
    # "TAG=PATH": extra writable host directories, mounted at their own path.
    mkdir -p "/newroot${s#*=}"
    mount -t 9p -o trans=virtio,version=9p2000.L,msize=512000 "${s%%=*}" "/newroot${s#*=}" || fail "mount share $s"
done
mount --move /proc /newroot/proc
mount --move /sys /newroot/sys
mount --move /dev /newroot/dev
exec switch_root /newroot /bin/bash "$rpath/guest.sh"
