#!/usr/bin/env bash
# Cross-builds libblvd and the tests of what a vehicle runs for arm64 with
# Debian's multiarch toolchain (packaging/cross/aarch64-linux-gnu.cmake), then
# runs them under qemu-aarch64 through CTest (label arm64):
#   arm64.sh HOST_BUILD_DIR [ARM64_BUILD_DIR]
# HOST_BUILD_DIR is a native build that has baked test-monaco.blvd (test
# bake.monaco_geofabrik): the bake is a host's tool and is not cross-built.
# Prints the cross-build and test times; writes them to ARM64_BUILD_DIR/times.txt.
set -euo pipefail
cd "$(dirname "$0")/../.."
host=$(realpath "${1:?usage: arm64.sh HOST_BUILD_DIR [ARM64_BUILD_DIR]}")
dir=${2:-build-arm64}
package=$host/test-monaco.blvd
[ -f "$package" ] || { echo "arm64.sh: $package missing: run ctest -R bake.monaco_geofabrik in $host" >&2; exit 2; }
bash packaging/scripts/deps_arm64.sh
mkdir -p "$dir"

# libgeographiclib-dev:arm64 cannot be installed beside the amd64 one (not
# Multi-Arch: same): unpack it with its library into a root of its own.
side=$(realpath "$dir")/geographiclib-root
if [ ! -f "$side/usr/include/GeographicLib/Config.h" ]; then
  geo_rt=$(apt-cache depends libgeographiclib-dev | awk '/Depends: libgeographiclib[0-9]/ {print $2; exit}')
  rm -rf "$side" "$dir/debs" && mkdir -p "$side" "$dir/debs"
  (cd "$dir/debs" && apt-get download -q libgeographiclib-dev:arm64 "$geo_rt:arm64" 2>&1 | grep -v "unsandboxed" || true)
  for deb in "$dir"/debs/*.deb; do dpkg-deb -x "$deb" "$side"; done
fi

cmake -S . -B "$dir" -G Ninja -DCMAKE_TOOLCHAIN_FILE="$PWD/packaging/cross/aarch64-linux-gnu.cmake" \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DBLVD_WERROR=ON -DBLVD_BUILD_TOOLS=OFF -DBLVD_BUILD_SAMPLES=OFF \
  -DBLVD_BUILD_TESTS=ON -DBLVD_PREBAKED_PACKAGE="$package" \
  -DGeographicLib_LIBRARIES="$side/usr/lib/aarch64-linux-gnu/libGeographicLib.so" > /dev/null
t0=$(date +%s)
cmake --build "$dir" -j"$(nproc)"
t1=$(date +%s)
set +e
ctest --test-dir "$dir" --output-on-failure -j"$(nproc)" -L arm64 --timeout 900 2>&1 | tee "$dir/ctest.log"
rc=${PIPESTATUS[0]}
set -e
t2=$(date +%s)
printf 'arm64 cross-build: %d s (%d jobs); arm64 tests under qemu-aarch64: %d s\n' \
  $((t1 - t0)) "$(nproc)" $((t2 - t1)) | tee "$dir/times.txt"
exit "$rc"
