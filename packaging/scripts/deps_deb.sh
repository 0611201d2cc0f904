#!/usr/bin/env bash
# What packaging/scripts/deb.sh needs beside deps.sh's (which installs the
# build dependencies): Debian's packaging tools and mmdebstrap for a clean root.
set -euo pipefail
export DEBIAN_FRONTEND=noninteractive
pkgs=(dpkg-dev debhelper lintian mmdebstrap)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
apt-get update -q
apt-get install -y -q --no-install-recommends "${missing[@]}"
