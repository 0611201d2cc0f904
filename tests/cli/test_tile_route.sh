#!/usr/bin/env bash
# `blvd bake --tile 2x2` end to end: 4x the blocks, cells and buildings, the
# package verifies, and `--impostor-route auto:N --seed S` picks the same
# cells in the 1x and the 2x2 package (META impostor_route), which carry
# impostors for them (the 2x2 one in every copy).
# Usage: test_tile_route.sh BLVD_EXE OSM WORKDIR
set -euo pipefail
blvd=$1 osm=$2 work=$3
mkdir -p "$work"
for t in 1x1 2x2; do
  "$blvd" bake --quiet "$osm" -o "$work/$t.blvd" --impostor single --impostor-route auto:4 --seed 5 --tile $t > /dev/null
  "$blvd" pack verify "$work/$t.blvd" > /dev/null
  "$blvd" pack info "$work/$t.blvd" --json > "$work/$t.json"
done
python3 - "$work/1x1.json" "$work/2x2.json" <<'PY'
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
for k in ("blocks", "cells", "buildings", "junctions", "triangles", "blobs"):
    assert b["counts"][k] == 4 * a["counts"][k], (k, a["counts"][k], b["counts"][k])
ra, rb = a["meta"]["impostor_route"], b["meta"]["impostor_route"]
assert 1 <= len(ra) <= 4 and ra == rb, (ra, rb)
tile = b["meta"]["tile"]
assert tile["nx"] == 2 and tile["ny"] == 2 and tile["cells_per_tile"] == a["counts"]["cells"], tile
assert all(c < tile["cells_per_tile"] for c in ra), ra
# Same per-cell and per-block pool sizing (blob bytes aside: copies carry a node translation).
for k, v in a["pool_sizing"].items():
    if "blob_bytes" not in k:
        assert b["pool_sizing"][k] == v, (k, v, b["pool_sizing"][k])
assert a["pool_sizing"]["max_cell_impostor_layers"] >= 1, a["pool_sizing"]
for l in range(4):
    assert b["lod_levels"][l]["blocks"] == 4 * a["lod_levels"][l]["blocks"], l
print("tile: route", ra, "in both packages;", b["counts"]["blocks"], "blocks")
PY
