#!/usr/bin/env bash
# Prepares an arm64 cross build of endotower on a Debian 12 (amd64) host:
#  - the host tools, installed with apt: Debian's cross compiler
#    (g++-aarch64-linux-gnu) and qemu-user-static (runs the arm64 unit tests);
#  - an arm64 sysroot made of Debian 12's own arm64 -dev packages and their
#    dependencies, downloaded with apt into a private state (its own package lists,
#    status and cache) and unpacked with dpkg-deb -x. Nothing is installed into the
#    host's dpkg database: libopencv-dev and libyaml-cpp-dev are not Multi-Arch: same,
#    so installing their arm64 packages would remove the host's amd64 ones.
# Usage: install-cross-deps.sh [SYSROOT]   (default: build/sysroot-arm64)
#        install-cross-deps.sh --host-tools  (only the host tools; CI installs them first
#        and then makes the sysroot beside its other steps, which use the host's apt)
# Safe to run again: the sysroot is rebuilt only when the package list changed.
set -euo pipefail

repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
host_only=0
if [ "${1:-}" = --host-tools ]; then host_only=1; shift; fi
sysroot=${1:-$repo/build/sysroot-arm64}
state=$sysroot.apt

host_packages=(g++-aarch64-linux-gnu qemu-user-static cmake pkg-config)
target_packages=(
  libc6-dev libstdc++-12-dev
  libopencv-dev libyaml-cpp-dev nlohmann-json3-dev libeigen3-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libdrm-dev libgbm-dev libegl-dev libgles-dev
  libgpiod-dev libhidapi-dev libusb-1.0-0-dev
  libfreetype-dev libdcmtk-dev
  libjpeg62-turbo-dev
)

sudo=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "endotower: need root (or sudo) to install ${host_packages[*]}" >&2; exit 1; }
  sudo=(sudo)
fi
export DEBIAN_FRONTEND=noninteractive

missing=()
for p in "${host_packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "endotower: installing host tools: ${missing[*]}" >&2
  "${sudo[@]}" apt-get update -q
  "${sudo[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
fi
if [ "$host_only" = 1 ]; then exit 0; fi

want="3 ${target_packages[*]}"  # bump the leading number when the unpacking changes
if [ -f "$sysroot/.endotower-packages" ] && [ "$(cat "$sysroot/.endotower-packages")" = "$want" ]; then
  exit 0
fi

# apt as if this were an arm64 machine with nothing installed, in a private state.
mkdir -p "$state/lists/partial" "$state/archives/partial" "$state/prefs.d"
: >"$state/status"
apt_opts=(-o "APT::Architecture=arm64" -o "APT::Architectures=arm64"
          -o "Dir::State::Lists=$state/lists" -o "Dir::State::status=$state/status"
          -o "Dir::Cache::archives=$state/archives" -o "Dir::Cache::pkgcache=" -o "Dir::Cache::srcpkgcache="
          -o "Dir::Etc::Preferences=$state/prefs" -o "Dir::Etc::PreferencesParts=$state/prefs.d"
          -o "Debug::NoLocking=1")
echo "endotower: downloading the arm64 sysroot packages into $state" >&2
apt-get "${apt_opts[@]}" update -q >&2
apt-get "${apt_opts[@]}" install --download-only -y -q --no-install-recommends "${target_packages[@]}" >&2

echo "endotower: unpacking the arm64 sysroot into $sysroot" >&2
rm -rf "$sysroot"
mkdir -p "$sysroot"
for deb in "$state"/archives/*.deb; do dpkg-deb -x "$deb" "$sysroot"; done
# dpkg-deb -x runs no maintainer scripts: make the update-alternatives links that
# the BLAS/LAPACK packages would (OpenCV links libblas.so.3 and liblapack.so.3).
lib=$sysroot/usr/lib/aarch64-linux-gnu
for so in libblas.so.3 liblapack.so.3; do
  for impl in "$lib"/*/"$so"; do
    [ -e "$impl" ] && [ ! -e "$lib/$so" ] && ln -s "${impl#"$lib"/}" "$lib/$so"
  done
done
# Absolute symlinks (e.g. libz.so -> /lib/aarch64-linux-gnu/libz.so.1.2.13) would point
# into the host: make them relative, inside the sysroot.
find "$sysroot" -type l -lname '/*' -print0 | while IFS= read -r -d '' link; do
  target=$(readlink "$link")
  ln -sfn "$(realpath -m --relative-to="$(dirname "$link")" "$sysroot$target")" "$link"
done
echo "$want" >"$sysroot/.endotower-packages"
echo "endotower: arm64 sysroot ready: $sysroot ($(du -sh "$sysroot" | cut -f1))" >&2
