#!/usr/bin/env bash
# dpkg-buildpackage -a ARCH: the Debian packages for a head unit, cross-built in
# a clean Debian 12 root of their own (mmdebstrap, the build machine's
# architecture + ARCH), because some build dependencies (libgeographiclib-dev,
# libosmium2-dev, libprotozero-dev) are not Multi-Arch: same and cannot be
# installed for ARCH beside the build machine's own. Then checks that every
# package of debian/control was made for ARCH, that libblvd0 holds an ARCH
# libblvd.so.0 in the multiarch folder, and runs lintian on them.
#   deb_cross.sh WORKDIR [ARCH]        (ARCH: arm64 unless given)
set -euo pipefail
cd "$(dirname "$0")/../.."
work=$(realpath -m "${1:?usage: deb_cross.sh WORKDIR [ARCH]}")
arch=${2:-arm64}
bash packaging/scripts/deps_deb.sh
version=$(dpkg-parsechangelog -l packaging/debian/changelog -S Version)
multiarch=$(dpkg-architecture -a "$arch" -qDEB_HOST_MULTIARCH 2>/dev/null)
tree=/in/blvd-$version
rm -rf "$work"
# shellcheck source=samples/step.sh
source samples/step.sh

bash packaging/scripts/deb_source.sh "$work/in/blvd-$version"
t0=$(date +%s)
step cross mmdebstrap --mode=root --variant=apt --architectures="$(dpkg --print-architecture),$arch" \
  --skip=download/empty --skip=cleanup/apt \
  --include="build-essential,crossbuild-essential-$arch,dpkg-dev,debhelper,pkgconf:$arch" \
  --setup-hook='mkdir -p "$1"/var/cache/apt/archives && cp -al /var/cache/apt/archives/*.deb "$1"/var/cache/apt/archives/' \
  --customize-hook="copy-in $work/in /" \
  --customize-hook="chroot \"\$1\" sh -c 'cd $tree && DEBIAN_FRONTEND=noninteractive apt-get build-dep -y -q -a $arch ./'" \
  --customize-hook="chroot \"\$1\" sh -c 'cd $tree && DEB_BUILD_OPTIONS=\"parallel=$(nproc) nocheck\" dpkg-buildpackage -a $arch -us -uc -b'" \
  bookworm "$work/root"
t1=$(date +%s)

out=$work/root/in
for p in $(sed -n 's/^Package: //p' packaging/debian/control); do
  f=$out/${p}_${version}_${arch}.deb
  [ -f "$f" ] || { echo "FAIL: dpkg-buildpackage -a $arch made no $f" >&2; exit 1; }
  [ "$(dpkg-deb -f "$f" Architecture)" = "$arch" ] || { echo "FAIL: $f is not Architecture: $arch" >&2; exit 1; }
done
lib=$work/libblvd0
dpkg-deb -x "$out/libblvd0_${version}_${arch}.deb" "$lib"
so=$lib/usr/lib/$multiarch/libblvd.so.0
[ -e "$so" ] || { echo "FAIL: libblvd0 has no usr/lib/$multiarch/libblvd.so.0" >&2; exit 1; }
machine=$(readelf -h "$so" | sed -n 's/^ *Machine: *//p')
echo "libblvd.so.0 ($arch): $machine"
bash packaging/scripts/lint.sh "$out/blvd_${version}_${arch}.changes" "$work/lintian.log"
printf 'dpkg-buildpackage -a %s in a clean root (root, build dependencies, build): %d s\n' "$arch" $((t1 - t0)) |
  tee "$work/times.txt"
