#!/usr/bin/env bash
# Installs blvd's build and test dependencies from Debian 12's archive.
# Runs as root (or with sudo available). Safe to run again.
set -euo pipefail
pkgs=(
  build-essential cmake ninja-build pkg-config python3
  libglm-dev libtinygltf-dev nlohmann-json3-dev libstb-dev libwebp-dev libdraco-dev libgeographiclib-dev
  libosmium2-dev libprotozero-dev zlib1g-dev libbz2-dev libexpat1-dev liblz4-dev libzip-dev
  libcgal-dev libgmp-dev libmpfr-dev libmeshoptimizer-dev libzstd-dev libcli11-dev
  libegl-dev libgles-dev libegl-mesa0 libgl1-mesa-dri libosmesa6-dev
  libgtest-dev libgmock-dev libbenchmark-dev gpsd gpsd-clients
  libx11-dev libssl-dev libcurl4-openssl-dev
  # tests/fuzz: coverage-guided fuzzing (libFuzzer ships in clang's runtime libraries).
  clang libclang-rt-14-dev
  # tests/remote: a real HTTP server started by the tests.
  nginx-light
  # tests/cluster: a one-node Slurm cluster started by the test itself.
  slurm-wlm munge
  # tests/vcan: the qemu guest with a vcan bus. Its kernel, busybox-static and
  # can-utils are fetched by `apt-get download` into the build folder, never installed.
  qemu-system-x86 zstd xz-utils
)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "deps: all ${#pkgs[@]} packages present"
  exit 0
fi
SUDO=""
[ "$(id -u)" = 0 ] || SUDO=sudo
echo "deps: installing ${missing[*]}"
$SUDO apt-get -o DPkg::Lock::Timeout=600 update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get -o DPkg::Lock::Timeout=600 install -y -qq --no-install-recommends "${missing[@]}"
