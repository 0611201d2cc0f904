#!/usr/bin/env bash
# The main job on the bundled defaults: install dependencies, build, bake the
# bundled Monaco extract, and drive a scripted path through it to PNG frames
# plus out/drive/index.html.
set -euo pipefail
cd "$(dirname "$0")/../.."
bash packaging/scripts/deps.sh
bash packaging/scripts/configure.sh demo build
cmake --build build --target blvd_cli
mkdir -p out
./build/sdk/cli/blvd bake data/osm/monaco-geofabrik-2026.osm.pbf -o out/monaco.blvd --report out/bake-report
./build/sdk/cli/blvd pack info out/monaco.blvd
./build/sdk/cli/blvd view out/monaco.blvd --path auto:12 --seed 7 --step 12 --with-full -o out/drive
echo "open out/drive/index.html (frames) and out/bake-report/index.html (bake report)"
