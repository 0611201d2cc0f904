#!/usr/bin/env bash
# The Debian source tree of this checkout in DEST (tracked and untracked files,
# no build folders), with packaging/debian as debian/: what deb.sh and
# deb_cross.sh hand to dpkg-buildpackage.
#   deb_source.sh DEST
set -euo pipefail
dest=${1:?usage: deb_source.sh DEST}
cd "$(dirname "$0")/../.."
mkdir -p "$dest"
git ls-files -co --exclude-standard -z | tar --null -T - -cf - | tar -xf - -C "$dest"
cp -r packaging/debian "$dest/debian"
