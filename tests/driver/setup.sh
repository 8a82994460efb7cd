#!/usr/bin/env bash
# Prepares the qemu guest that runs the driver tests against real kernel drivers
# (vivid, uhid, gpio-sim, vkms): Debian's own kernel, two modules Debian does not
# build (gpio-sim, vkms) built out of tree from linux-source-6.1, and a busybox
# initramfs that mounts the host's root read-only. Facts and traps:
# ../shared/docs/virtual-hardware.md.
#
# Usage: tests/driver/setup.sh [CACHE_DIR]      (default: build/vhw in the repo)
# Prints the prepared directory (CACHE_DIR/KVER) on stdout. Reruns are instant
# once CACHE_DIR/KVER/ready exists. Exit 77 when the guest cannot be prepared on
# this machine at all (no qemu, no kernel package obtainable), with the reason on
# stderr; exit 1 when a step fails.
set -euo pipefail

repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
cache=${1:-$repo/build/vhw}
say() { echo "vhw-setup: $*" >&2; }
skip() { say "SKIP: $*"; exit 77; }
die() { say "ERROR: $*"; exit 1; }

# Installs Debian packages when root (CI), otherwise names them.
need_packages() {
    local missing=() p
    for p in "$@"; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
    done
    [ ${#missing[@]} -eq 0 ] && return 0
    if [ "$(id -u)" -eq 0 ]; then
        say "installing ${missing[*]}"
        DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}" >&2 \
            || { DEBIAN_FRONTEND=noninteractive apt-get update -q >&2 &&
                 DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}" >&2; } \
            || return 1
    else
        say "missing Debian packages: ${missing[*]} (run toolchain/install-deps.sh as root)"
        return 1
    fi
}

# The guest kernel: ENDOTOWER_GUEST_KVER, else the newest installed 6.1 headers.
kver=${ENDOTOWER_GUEST_KVER:-}
if [ -z "$kver" ]; then
    kver=$(ls -d /usr/src/linux-headers-6.1.0-*-amd64 2>/dev/null | sed 's|.*/linux-headers-||' | sort -V | tail -n1 || true)
fi
if [ -z "$kver" ]; then
    need_packages linux-headers-amd64 || skip "no linux-headers-6.1.0-*-amd64 installed and none installable"
    kver=$(ls -d /usr/src/linux-headers-6.1.0-*-amd64 | sed 's|.*/linux-headers-||' | sort -V | tail -n1)
fi
out=$cache/$kver
if [ -f "$out/ready" ]; then echo "$out"; exit 0; fi

need_packages qemu-system-x86 || skip "qemu-system-x86 is not installed and cannot be installed here"
command -v qemu-system-x86_64 >/dev/null || skip "qemu-system-x86_64 not found"
need_packages busybox-static kmod "linux-headers-$kver" linux-source-6.1 build-essential udev \
    v4l-utils gpiod libdrm-tests \
    || die "packages missing (see above)"

mkdir -p "$cache"
# Two test binaries may start at once: one prepares, the other waits.
exec 9>"$cache/.lock"
flock 9
if [ -f "$out/ready" ]; then echo "$out"; exit 0; fi
rm -rf "$out"
mkdir -p "$out/work"
work=$out/work
t0=$(date +%s)

# 1. Debian's kernel package for the same version as the headers.
deb=$(ls /var/cache/apt/archives/linux-image-"$kver"_*.deb 2>/dev/null | head -n1 || true)
if [ -z "$deb" ]; then
    (cd "$work" && apt-get download "linux-image-$kver" >&2) \
        || skip "cannot download linux-image-$kver (apt-get download failed: no network or no package lists?)"
    deb=$(ls "$work"/linux-image-"$kver"_*.deb | head -n1)
fi
say "unpacking $(basename "$deb")"
dpkg-deb -x "$deb" "$out/root"
mods=$out/root/lib/modules/$kver
[ -d "$mods" ] || die "$deb has no lib/modules/$kver"

# 2. The few source files needed, out of the 132 MB tarball.
src=/usr/src/linux-source-6.1.tar.xz
top=$(tar -tJf "$src" 2>/dev/null | head -n1 | cut -d/ -f1 || true)
[ -n "$top" ] || die "cannot list $src"
say "extracting gpio-sim, irq_sim, vkms and extract-vmlinux from $src"
tar -xJf "$src" -C "$work" "$top/drivers/gpio/gpio-sim.c" "$top/drivers/gpio/gpiolib.h" \
    "$top/kernel/irq/irq_sim.c" "$top/drivers/gpu/drm/vkms" "$top/scripts/extract-vmlinux"
ksrc=$work/$top

# 3. gpio-sim with irq_sim merged in (Debian has CONFIG_IRQ_SIM unset); irq_to_desc
#    is not exported, so irq_sim's handle_simple_irq(irq_to_desc(n)) becomes
#    generic_handle_irq(n).
gs=$work/gpio-sim
mkdir -p "$gs"
cp "$ksrc/drivers/gpio/gpio-sim.c" "$gs/gpio-sim-main.c"
cp "$ksrc/drivers/gpio/gpiolib.h" "$gs/"
sed 's/handle_simple_irq(irq_to_desc(\([a-z_]*\)))/generic_handle_irq(\1)/' \
    "$ksrc/kernel/irq/irq_sim.c" >"$gs/irq_sim.c"
grep -q 'generic_handle_irq(' "$gs/irq_sim.c" || die "irq_sim.c: the handle_simple_irq patch did not apply"
printf 'obj-m := gpio-sim.o\ngpio-sim-y := gpio-sim-main.o irq_sim.o\n' >"$gs/Kbuild"
say "building gpio-sim.ko"
make -s -C "/usr/src/linux-headers-$kver" M="$gs" modules >&2 || die "building gpio-sim failed"

# 4. vkms unchanged.
vk=$work/vkms
cp -r "$ksrc/drivers/gpu/drm/vkms" "$vk"
say "building vkms.ko"
make -s -C "/usr/src/linux-headers-$kver" M="$vk" CONFIG_DRM_VKMS=m modules >&2 || die "building vkms failed"

mkdir -p "$mods/extra"
cp "$gs/gpio-sim.ko" "$vk/vkms.ko" "$mods/extra/"
depmod -b "$out/root" "$kver" || die "depmod failed"

# 5. The uncompressed kernel: q35 + vmlinux boots in ~3 s instead of ~7 s.
sh "$ksrc/scripts/extract-vmlinux" "$out/root/boot/vmlinuz-$kver" >"$out/vmlinux" \
    || die "extract-vmlinux failed on vmlinuz-$kver"

# 6. busybox initramfs: loads virtio + 9p + overlay, mounts the host root, hands over.
ird=$work/initramfs
mkdir -p "$ird/bin" "$ird/modules" "$ird/proc" "$ird/sys" "$ird/dev" "$ird/newroot" "$ird/lower" "$ird/rw" "$ird/results"
cp /bin/busybox "$ird/bin/busybox"
: >"$ird/modules/order"
for m in virtio_ring virtio virtio_pci_modern_dev virtio_pci_legacy_dev virtio_pci netfs fscache 9pnet 9pnet_virtio 9p overlay; do
    f=$(find "$mods/kernel" -name "$m.ko*" | head -n1)
    [ -n "$f" ] || { say "$m is built into $kver"; continue; }
    case "$f" in
        *.ko.xz) xz -dc "$f" >"$ird/modules/$m.ko" ;;
        *.ko.zst) zstd -qdc "$f" >"$ird/modules/$m.ko" ;;
        *) cp "$f" "$ird/modules/$m.ko" ;;
    esac
    echo "$m" >>"$ird/modules/order"
done
cp "$repo/tests/driver/guest-initramfs-init.sh" "$ird/init"
chmod +x "$ird/init"
(cd "$ird" && find . | busybox cpio -o -H newc 2>/dev/null) >"$out/initramfs.cpio"

rm -rf "$work"
touch "$out/ready"
say "guest ready in $out ($(($(date +%s) - t0)) s)"
echo "$out"
