#!/usr/bin/env bash
# Installs the Debian 12 packages endotower builds and tests with, if any is missing.
# Safe to run again: it only calls apt-get when something is absent.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libopencv-dev libopencv-contrib-dev libeigen3-dev
  libyaml-cpp-dev nlohmann-json3-dev
  libgpiod-dev libhidapi-dev libusb-1.0-0-dev
  libdrm-dev libgbm-dev libegl-dev libgles-dev libegl-mesa0
  libgtest-dev libgmock-dev libbenchmark-dev
  # the libFuzzer targets (toolchain/fuzz.sh, run by CI)
  clang libclang-rt-14-dev
  # the qemu guest of tests/driver (real kernel drivers: vivid, uhid, gpio-sim, vkms)
  qemu-system-x86 busybox-static kmod linux-headers-amd64 linux-source-6.1 bc
  v4l-utils gpiod libdrm-tests udev
  # display driver (issue 9): DRM/KMS, GBM, EGL, GLES2; Mesa's llvmpipe for the headless
  # overlay test and for vkms in the guest
  libdrm-dev libgbm-dev libegl-dev libgles-dev libegl-mesa0 libgl1-mesa-dri
  # overlay renderer (issue 8): FreeType and the DejaVu font for text; DCMTK for DICOM
  libfreetype-dev fonts-dejavu-core libdcmtk-dev
  # reliability (issue 10): clang-tidy (toolchain/tidy.sh), strace (the no-network test),
  # systemd-analyze (the unit's security score, docs/reliability.md)
  clang-tidy strace systemd
  # MJPEG capture (issue 9): libjpeg-turbo
  libjpeg62-turbo-dev
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "endotower: installing Debian packages: ${missing[*]}" >&2
sudo=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "endotower: need root (or sudo) to install: ${missing[*]}" >&2; exit 1; }
  sudo=(sudo)
fi
export DEBIAN_FRONTEND=noninteractive
"${sudo[@]}" apt-get update -q
"${sudo[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
