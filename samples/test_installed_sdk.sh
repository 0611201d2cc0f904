#!/usr/bin/env bash
# The samples build against the installed SDK, not only in-tree: install this
# build into a temporary prefix and check it as a host would use it
# (check_installed_sdk.sh: pkg-config, find_package(blvd), every sample run).
# Usage: test_installed_sdk.sh BUILD_DIR SOURCE_DIR PACKAGE WORKDIR
set -euo pipefail
build=$1 src=$2 pkg=$3 work=$4
rm -rf "$work"
mkdir -p "$work"

# shellcheck source=samples/step.sh
source "$(dirname "$0")/step.sh"

step install cmake --install "$build" --prefix "$work/prefix"
prefix=$work/prefix
"$src/samples/check_installed_sdk.sh" "$prefix" "$prefix/lib" "$src" "$pkg" "$work/check"
