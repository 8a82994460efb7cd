#!/usr/bin/env bash
# Installs what an arm64 cross build of endotower needs on a Debian 12 (amd64) host:
# Debian's cross compiler, the arm64 (multiarch) -dev packages of every library the
# project links, and qemu-user-static to run the arm64 unit tests on the host.
# Safe to run again: apt-get is called only when something is missing.
set -euo pipefail

arch=arm64
host_packages=(g++-aarch64-linux-gnu cmake pkg-config qemu-user-static binfmt-support)
target_packages=(
  libopencv-dev libyaml-cpp-dev libgtest-dev libgmock-dev libbenchmark-dev
  libdrm-dev libgbm-dev libegl-dev libgles-dev
  libgpiod-dev libhidapi-dev libusb-1.0-0-dev
)
# Header-only, architecture independent.
all_packages=(nlohmann-json3-dev)

sudo=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "endotower: need root (or sudo) to install packages" >&2; exit 1; }
  sudo=(sudo)
fi
export DEBIAN_FRONTEND=noninteractive

wanted=("${host_packages[@]}" "${all_packages[@]}")
for p in "${target_packages[@]}"; do wanted+=("$p:$arch"); done
missing=()
for p in "${wanted[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

if ! dpkg --print-foreign-architectures | grep -qx "$arch"; then
  "${sudo[@]}" dpkg --add-architecture "$arch"
fi
echo "endotower: installing for the $arch cross build: ${missing[*]}" >&2
"${sudo[@]}" apt-get update -q
"${sudo[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
