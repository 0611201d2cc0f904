#!/usr/bin/env bash
# The samples build against the installed SDK, not only in-tree: install this
# build into a temporary prefix, configure samples/host_context on its own
# with find_package(blvd) from that prefix, build it and run it.
# Usage: test_installed_sdk.sh BUILD_DIR SOURCE_DIR PACKAGE WORKDIR
set -euo pipefail
build=$1 src=$2 pkg=$3 work=$4
rm -rf "$work"
mkdir -p "$work"
cmake --install "$build" --prefix "$work/prefix" > "$work/install.log"
test -f "$work/prefix/lib/cmake/blvd/blvdConfig.cmake"
test -f "$work/prefix/include/blvd/blvd.h"
cmake -S "$src/samples/host_context" -B "$work/host_context" -DCMAKE_PREFIX_PATH="$work/prefix" > "$work/configure.log"
cmake --build "$work/host_context" > "$work/build.log"
# It must use the installed library, not the build tree's.
ldd "$work/host_context/host_context" | grep "$work/prefix/lib/libblvd.so.0" > /dev/null
"$work/host_context/host_context" "$pkg" -o "$work/frame.png"
