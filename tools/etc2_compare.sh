#!/usr/bin/env bash
# The ETC2 encoder of revision REV against the working tree's, on the impostor
# images of a package's cells (tools/etc2_compare.cpp):
#   tools/etc2_compare.sh REV PACKAGE [FIRST_CELL [CELL_STEP [IMAGES]]]
# The images come from tools/layer_images.py (25 by default); both encoders
# are built into one program (-O3, as libblvd builds the encoder). Needs a built tree (build/sdk/cli/blvd).
set -euo pipefail
cd "$(dirname "$0")/.."
rev=${1:?usage: etc2_compare.sh REV PACKAGE [FIRST_CELL [CELL_STEP [IMAGES]]]}
pkg=${2:?usage: etc2_compare.sh REV PACKAGE [FIRST_CELL [CELL_STEP [IMAGES]]]}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
git show "$rev:sdk/render/etc2.cpp" | sed 's/namespace blvd::render/namespace old_etc2/; s|"render/etc2.h"|"old_etc2.h"|' \
  > "$work/old_etc2.cpp"
git show "$rev:sdk/render/etc2.h" | sed 's/namespace blvd::render/namespace old_etc2/' > "$work/old_etc2.h"
g++ -O3 -std=c++17 -Isdk -Itools -I"$work" tools/etc2_compare.cpp "$work/old_etc2.cpp" sdk/render/etc2.cpp -o "$work/compare"
tools/layer_images.py "$pkg" "$work" "${@:3}" > "$work/args"
# shellcheck disable=SC2046
"$work/compare" $(cat "$work/args")
