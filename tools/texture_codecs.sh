#!/usr/bin/env bash
# WebP against AVIF for impostor atlases (tools/texture_codecs.cpp), on layer
# images of a package baked near-losslessly:
#   tools/texture_codecs.sh PACKAGE [FIRST_CELL [CELL_STEP [IMAGES]]]
# PACKAGE should hold its atlases as JPEG at quality 100 (4:4:4), e.g.
#   blvd bake data/osm/monaco-osrm-2016.osm.pbf -o q100.blvd --impostor layered \
#     --impostor-route auto:200 --seed 1 --texture-codec jpeg --texture-quality 100
# Needs libavif-dev and libwebp-dev (apt-get install libavif-dev) and a built
# tree (build/sdk/cli/blvd). Prints a Markdown table.
set -euo pipefail
cd "$(dirname "$0")/.."
pkg=${1:?usage: texture_codecs.sh PACKAGE [FIRST_CELL [CELL_STEP [IMAGES]]]}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# shellcheck disable=SC2046
g++ -O2 -std=c++17 -Itools tools/texture_codecs.cpp -o "$work/codecs" $(pkg-config --cflags --libs libavif libwebp)
tools/layer_images.py "$pkg" "$work" "${@:2}" > "$work/args"
# shellcheck disable=SC2046
"$work/codecs" $(cat "$work/args")
