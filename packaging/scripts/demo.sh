#!/usr/bin/env bash
# The main job on the bundled defaults: install dependencies, build, bake the
# bundled Monaco extract, and drive a scripted path through it to PNG frames
# plus out/drive/index.html.
# Usage: packaging/scripts/demo.sh [--terrain]
#   --terrain  the same on the bundled SRTM tile (the city climbing from the
#              harbour): out/monaco-terrain.blvd and out/drive-terrain/
set -euo pipefail
cd "$(dirname "$0")/../.."
pkg=out/monaco.blvd drive=out/drive report=out/bake-report dem=()
case "${1:-}" in
  "") ;;
  --terrain) pkg=out/monaco-terrain.blvd drive=out/drive-terrain report=out/bake-report-terrain
             dem=(--dem data/dem/N43E007.hgt.zip) ;;
  *) echo "demo.sh: unknown option $1 (expected --terrain or nothing)" >&2; exit 2 ;;
esac
bash packaging/scripts/deps.sh
bash packaging/scripts/configure.sh demo build
cmake --build build --target blvd_cli
mkdir -p out
./build/sdk/cli/blvd bake data/osm/monaco-geofabrik-2026.osm.pbf -o "$pkg" "${dem[@]}" --report "$report"
./build/sdk/cli/blvd pack info "$pkg"
./build/sdk/cli/blvd view "$pkg" --path auto:12 --seed 7 --step 12 --with-full -o "$drive"
echo "open $drive/index.html (frames) and $report/index.html (bake report)"
