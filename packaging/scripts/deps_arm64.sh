#!/usr/bin/env bash
# What the arm64 cross-build and its emulated tests need, beside deps.sh's:
# Debian's cross toolchain, qemu's user-mode emulator, and the :arm64 packages
# of libblvd's dependencies, its test framework and Mesa (llvmpipe for EGL and
# OSMesa). Multiarch installs them in /usr/lib/aarch64-linux-gnu.
# libgeographiclib-dev is not Multi-Arch: same (it cannot sit beside the amd64
# one): arm64.sh unpacks it into a root of its own. The bake's dependencies
# (CGAL, libosmium) are not here: the cross-build has no tools.
set -euo pipefail
export DEBIAN_FRONTEND=noninteractive
geo_rt=$(apt-cache depends libgeographiclib-dev | awk '/Depends: libgeographiclib[0-9]/ {print $2; exit}')
pkgs=(crossbuild-essential-arm64 qemu-user pkgconf:arm64
  libgtest-dev:arm64 libgmock-dev:arm64 libdraco-dev:arm64 libmeshoptimizer-dev:arm64 libwebp-dev:arm64
  libstb-dev:arm64 libosmesa6-dev:arm64 libegl-dev:arm64 libgles-dev:arm64 libopengl-dev:arm64 libgl-dev:arm64 libcurl4-openssl-dev:arm64
  zlib1g-dev:arm64 libzstd-dev:arm64 "${geo_rt}:arm64" libegl-mesa0:arm64 libgl1-mesa-dri:arm64)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
if ! dpkg --print-foreign-architectures | grep -qx arm64; then
  dpkg --add-architecture arm64
fi
apt-get update -q
apt-get install -y -q --no-install-recommends "${missing[@]}"
