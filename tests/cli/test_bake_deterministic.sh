#!/usr/bin/env bash
# The bake is deterministic: two bakes of the same input with the same options
# give byte-identical packages (impostor captures and LOD chains included, and
# a tiled --tile 2x2 package too), with one capture worker or three.
set -euo pipefail
blvd=$1 osm=$2 work=$3
mkdir -p "$work"
for i in 1 2; do
  jobs=$((i == 1 ? 1 : 3))
  "$blvd" bake --quiet "$osm" -o "$work/det$i.blvd" --impostor both --impostor-route auto:8 --seed 3 --jobs $jobs > /dev/null
  "$blvd" bake --quiet "$osm" -o "$work/tile$i.blvd" --impostor none --tile 2x2 > /dev/null
done
cmp "$work/det1.blvd" "$work/det2.blvd"
cmp "$work/tile1.blvd" "$work/tile2.blvd"
echo "bake determinism: $(stat -c %s "$work/det1.blvd") and $(stat -c %s "$work/tile1.blvd") (2x2) identical bytes (1 and 3 capture workers)"
