#!/usr/bin/env bash
# Every benchmark of docs/benchmarks.md on the bundled data, one after
# another, then the tables rewritten from their JSON (tools/bench_doc.py).
# Needs a built tree (either README command).
# Usage: packaging/scripts/bench.sh [OUT_DIR [monaco|sf|all]]
# (default out/bench all); a partial run keeps the other cities' results.
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-out/bench}
which=${2:-all}
mkdir -p "$out"
blvd=./build/sdk/cli/blvd
[ -x "$blvd" ] || { echo "bench.sh: $blvd is missing: run a README command first" >&2; exit 2; }
osm=data/osm
touch "$out/commands.tsv"

# `run NAME CMD...`: runs CMD, and records it as the command of NAME's table.
run() {
  local name=$1; shift
  echo "== $name: $*" >&2
  "$@"
  grep -v -P "^\Q$name\E\t" "$out/commands.tsv" > "$out/commands.tsv.new" || true
  printf '%s\t%s\n' "$name" "$*" >> "$out/commands.tsv.new"
  mv "$out/commands.tsv.new" "$out/commands.tsv"
}

monaco() {
  run bake.none /usr/bin/time -f "%e s" -o "$out/bake-none.time" \
    "$blvd" bake --quiet "$osm/monaco-osrm-2016.osm.pbf" -o "$out/osrm-none.blvd" --impostor none > "$out/bake-none.txt"
  "$blvd" pack info --json "$out/osrm-none.blvd" > "$out/bake-none.json"
  run bake.route /usr/bin/time -f "%e s" -o "$out/bake-route.time" \
    "$blvd" bake --quiet "$osm/monaco-osrm-2016.osm.pbf" -o "$out/osrm.blvd" \
    --impostor both --impostor-route auto:200 --seed 1 > "$out/bake-route.txt"
  "$blvd" pack info --json "$out/osrm.blvd" > "$out/bake-route.json"
  run route "$blvd" bench route "$out/osrm.blvd" --route auto:200 --seed 1 --json "$out/route.json"
  run route.etc2 "$blvd" bench route "$out/osrm.blvd" --route auto:200 --seed 1 --impostor-texture etc2 \
    --json "$out/route.etc2.json"
  run budget "$blvd" bench budget "$out/osrm.blvd" --route auto:120 --seed 1 --json "$out/budget.json"
  run bake.demo /usr/bin/time -f "%e s" -o "$out/bake-demo.time" \
    "$blvd" bake --quiet "$osm/monaco-geofabrik-2026.osm.pbf" -o "$out/demo.blvd" > "$out/bake-demo.txt"
  "$blvd" pack info --json "$out/demo.blvd" > "$out/bake-demo.json"
  run route.demo "$blvd" bench route "$out/demo.blvd" --route auto:12 --seed 7 --step 12 --json "$out/route.demo.json"
  run route.demo.etc2 "$blvd" bench route "$out/demo.blvd" --route auto:12 --seed 7 --step 12 \
    --impostor-texture etc2 --json "$out/route.demo.etc2.json"
  run decode.demo "$blvd" bench decode "$out/demo.blvd" --json "$out/decode.demo.json"
  # The former bake defaults (decision 0015), and the same in WebP.
  "$blvd" bake --quiet "$osm/monaco-osrm-2016.osm.pbf" -o "$out/osrm-jpeg1x.blvd" --impostor both \
    --impostor-route auto:200 --seed 1 --texture-codec jpeg --cell-texels 163840 --run-length 100 --max-runs 4
  "$blvd" bake --quiet "$osm/monaco-osrm-2016.osm.pbf" -o "$out/osrm-webp1x.blvd" --impostor both \
    --impostor-route auto:200 --seed 1 --cell-texels 163840 --run-length 100 --max-runs 4
  # The route package with its blobs stored as they are (decision 0029).
  "$blvd" bake --quiet "$osm/monaco-osrm-2016.osm.pbf" -o "$out/osrm-z0.blvd" --impostor both \
    --impostor-route auto:200 --seed 1 --blob-compression 0
  run decode "$blvd" bench decode "$out/osrm.blvd" "$out/osrm-jpeg1x.blvd" "$out/osrm-webp1x.blvd" \
    "$out/osrm-none.blvd" "$out/osrm-z0.blvd" --rounds 3 --json "$out/decode.json"
  "$blvd" bake --quiet "$osm/monaco-geofabrik-2026.osm.pbf" -o "$out/m1.blvd" --impostor both --impostor-route auto:40 --seed 7
  "$blvd" bake --quiet "$osm/monaco-geofabrik-2026.osm.pbf" -o "$out/m4.blvd" --impostor both --impostor-route auto:40 \
    --seed 7 --tile 2x2
  run memory "$blvd" bench memory "$out/m1.blvd" "$out/m4.blvd" --route auto:40 --seed 7 --laps 2 --json "$out/memory.json"
  "$blvd" bake --quiet "$osm/monaco-geofabrik-2026.osm.pbf" -o "$out/m16.blvd" --impostor both --impostor-route auto:40 \
    --seed 7 --tile 4x4
  run scale "$blvd" bench scale "$out/m1.blvd" "$out/m4.blvd" "$out/m16.blvd" --route auto:40 --seed 7 \
    --json "$out/scale.json" --html "$out/scale"
  run track "$blvd" bench track --quiet --package "$out/m1.blvd" --data tests/data -o "$out/track.json"
}

sf() {
  run bake.sf /usr/bin/time -f "%e s" -o "$out/bake-sf.time" \
    "$blvd" bake --quiet "$osm/sf-downtown-2023.osm.pbf" -o "$out/sf.blvd" \
    --impostor both --impostor-route auto:100 --seed 1 > "$out/bake-sf.txt"
  "$blvd" pack info --json "$out/sf.blvd" > "$out/bake-sf.json"
  run route.sf "$blvd" bench route "$out/sf.blvd" --route auto:100 --seed 1 --json "$out/route.sf.json"
  run route.sf.etc2 "$blvd" bench route "$out/sf.blvd" --route auto:100 --seed 1 --impostor-texture etc2 \
    --json "$out/route.sf.etc2.json"
  run decode.sf "$blvd" bench decode "$out/sf.blvd" --json "$out/decode.sf.json"
  run budget.sf "$blvd" bench budget "$out/sf.blvd" --route auto:100 --seed 1 --json "$out/budget.sf.json"
  "$blvd" bake --quiet "$osm/sf-downtown-2023.osm.pbf" -o "$out/sf4.blvd" --impostor both --impostor-route auto:40 \
    --seed 7 --tile 2x2
  "$blvd" bake --quiet "$osm/sf-downtown-2023.osm.pbf" -o "$out/sf1.blvd" --impostor both --impostor-route auto:40 --seed 7
  run memory.sf "$blvd" bench memory "$out/sf1.blvd" "$out/sf4.blvd" --route auto:40 --seed 7 --laps 2 \
    --json "$out/memory.sf.json"
}

case "$which" in
  monaco) monaco ;;
  sf) sf ;;
  all) monaco; sf ;;
  *) echo "bench.sh: expected monaco, sf or all, not $which" >&2; exit 2 ;;
esac
python3 tools/bench_doc.py "$out" docs/benchmarks.md
echo "docs/benchmarks.md: tables rewritten from $out" >&2
