#!/usr/bin/env bash
# Builds blvd's Debian packages and checks them as a user meets them:
#   deb.sh WORKDIR PACKAGE
# 1. the checkout (tracked and untracked files, no build folders) copied to
#    WORKDIR/blvd-VERSION, with packaging/debian as debian/;
# 2. dpkg-buildpackage -us -uc -b (dpkg-gensymbols checks libblvd0.symbols);
# 3. lintian: no error, and every warning's tag explained in packaging/debian/README (lint.sh);
# 4. a clean Debian 12 root made by mmdebstrap (packages from the local apt
#    cache where it has them), where `apt-get install ./*.deb` installs the
#    packages and samples/check_installed_sdk.sh builds the samples against
#    /usr with find_package(blvd) and pkg-config and renders frames from
#    PACKAGE (a baked test-monaco.blvd).
set -euo pipefail
cd "$(dirname "$0")/../.."
src=$PWD
work=$(realpath -m "${1:?usage: deb.sh WORKDIR PACKAGE}")
pkg=$(realpath "${2:?usage: deb.sh WORKDIR PACKAGE}")
bash packaging/scripts/deps_deb.sh
arch=$(dpkg --print-architecture)
multiarch=$(dpkg-architecture -qDEB_HOST_MULTIARCH)
version=$(dpkg-parsechangelog -l packaging/debian/changelog -S Version)
tree=$work/blvd-$version
rm -rf "$work"
mkdir -p "$tree"

# shellcheck source=samples/step.sh
source samples/step.sh

# 1-2. Build.
bash packaging/scripts/deb_source.sh "$tree"
t0=$(date +%s)
step build env -C "$tree" DEB_BUILD_OPTIONS="parallel=$(nproc) nocheck" dpkg-buildpackage -us -uc -b
t1=$(date +%s)
debs=()
for p in $(sed -n 's/^Package: //p' packaging/debian/control); do
  f=$work/${p}_${version}_${arch}.deb
  [ -f "$f" ] || { echo "FAIL: dpkg-buildpackage made no $f" >&2; exit 1; }
  debs+=("$f")
done

# 3. lintian: errors fail; each warning's tag is named in the README's Lintian section.
bash packaging/scripts/lint.sh "$work/blvd_${version}_${arch}.changes" "$work/lintian.log"

# 4. A clean root: the packages from apt, the samples from this checkout.
root=$work/root
mkdir -p "$work/in/src/tests/data/can"
cp "${debs[@]}" "$work/in/"
cp "$pkg" "$work/in/test-monaco.blvd"
cp -r samples "$work/in/src/samples"
cp -r tests/data/can/dbc "$work/in/src/tests/data/can/dbc"
step root mmdebstrap --mode=root --variant=apt --skip=download/empty --skip=cleanup/apt \
  --include=build-essential,cmake,pkg-config,libcli11-dev,libstb-dev,libgles-dev,libopengl-dev \
  --setup-hook='mkdir -p "$1"/var/cache/apt/archives && cp -al /var/cache/apt/archives/*.deb "$1"/var/cache/apt/archives/' \
  --customize-hook="copy-in $work/in /" \
  --customize-hook='chroot "$1" sh -c "cd /in && DEBIAN_FRONTEND=noninteractive apt-get install -y -q ./*.deb"' \
  --customize-hook="chroot \"\$1\" /in/src/samples/check_installed_sdk.sh /usr /usr/lib/$multiarch /in/src /in/test-monaco.blvd /in/check" \
  bookworm "$root"
t2=$(date +%s)
test -f "$root/in/check/frame.png" || { echo "FAIL: no frame rendered in the clean root" >&2; exit 1; }
printf 'packages: %s\ndpkg-buildpackage: %d s; clean root, install and samples: %d s\n' \
  "${debs[*]##*/}" $((t1 - t0)) $((t2 - t1)) | tee "$work/times.txt"
