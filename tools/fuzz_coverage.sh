#!/usr/bin/env bash
# Source coverage of the fuzz targets' corpora, by llvm-cov:
#   tools/fuzz_coverage.sh [TARGET...]     every target when none is named
# Builds build-cov (BLVD_COVERAGE_BUILD to change it: clang, BLVD_FUZZ and
# BLVD_COVERAGE, no sanitizers), then replays each target once over what its
# campaigns kept (build-fuzz/fuzz/<target>/corpus, from tools/fuzz.sh) and its
# seeds, regressions and inputs, and counts the lines, functions, regions and
# branches reached in the sources that target is there to test (the table
# below). Writes out/coverage/index.html (BLVD_COVERAGE_OUT to change it), a
# summary.tsv and each target's annotated sources (llvm-cov's HTML).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${BLVD_COVERAGE_BUILD:-$root/build-cov}
corpora=${BLVD_FUZZ_BUILD:-$root/build-fuzz}/fuzz
out=${BLVD_COVERAGE_OUT:-$root/out/coverage}
profdata=$(command -v llvm-profdata-14 || command -v llvm-profdata) || { echo "fuzz_coverage.sh: no llvm-profdata (apt-get install llvm)" >&2; exit 2; }
llvmcov=$(command -v llvm-cov-14 || command -v llvm-cov) || { echo "fuzz_coverage.sh: no llvm-cov (apt-get install llvm)" >&2; exit 2; }

# The sources each target is there to test, as a regex over the repository's files.
declare -A sources=(
  [fuzz_cache_entry]='^sdk/remote/disk_cache\.'
  [fuzz_can_frame]='^sdk/capi/capi_vehicle|^sdk/vehicle/(profile|frame)'
  [fuzz_candump]='^adapters/can/candump\.'
  [fuzz_capi]='^sdk/capi/(capi_tracking|track_convert)'
  [fuzz_dbc]='^sdk/vehicle/dbc'
  [fuzz_dem]='^sdk/bake/dem\.'
  [fuzz_glb]='^sdk/package/(glb_decode|glb_detail|glb\.h|meshopt_view)'
  [fuzz_gpsd]='^adapters/gnss/gpsd_client\.'
  [fuzz_nmea]='^adapters/gnss/nmea'
  [fuzz_osm]='^sdk/bake/osm_reader'
  [fuzz_package]='^sdk/package/(reader|format|glb_decode|glb_detail|glb\.h|meshopt_view|table_pages)|^sdk/stream/(city|paged_graph|block_pages|cell_table_pages|page_cache|terrain_pages)|^sdk/graph/segment_grid'
  [fuzz_runtime]='^sdk/capi/(blvd_capi|binding)|^sdk/runtime/(block_copy|cell_choice|cell_loader|cell_slots|draw_list|frame|frame_clock|impostor_atlas|lod_choice|memory_plan|prefetch_share|runtime|slot_upload|terrain_set|tracking)\.'
  [fuzz_shard_manifest]='^sdk/bake/shard\.'
)

if [ ! -f "$build/build.ninja" ]; then
  CC=clang CXX=clang++ cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DBLVD_FUZZ=ON -DBLVD_COVERAGE=ON -DBLVD_BUILD_SAMPLES=OFF > /dev/null
fi
all=$(sed -n 's/^build tests\/fuzz\/\(fuzz_[a-z_]*\): .*/\1/p' "$build/build.ninja" | sort -u)
run=${*:-$all}
for t in $run; do
  grep -qx "$t" <<< "$all" || { echo "fuzz_coverage.sh: no fuzz target $t" >&2; exit 2; }
  [ -n "${sources[$t]:-}" ] || { echo "fuzz_coverage.sh: say which sources $t tests (the table in this script)" >&2; exit 2; }
done
# shellcheck disable=SC2086
ninja -C "$build" $run

mkdir -p "$out/rows"
for t in $run; do
  bin=$build/tests/fuzz/$t
  work=$build/coverage/$t
  rm -rf "$work" "${out:?}/$t"
  mkdir -p "$work/prof"
  extra=()
  [ -d "$corpora/$t/corpus" ] && extra+=("$corpora/$t/corpus")
  # A replay that ends on a find still leaves the profile of what ran before it.
  LLVM_PROFILE_FILE="$work/prof/%p.profraw" \
    bash "$root/tests/fuzz/campaign.sh" "$bin" "$build/tests/fuzz/$t.inputs" 0 "$work/replay" "${extra[@]}" \
    > "$work/replay.log" 2>&1 || echo "$t: the replay did not end cleanly (see $work/replay.log)" >&2
  inputs=$(sed -n 's/.*INFO: seed corpus: files: \([0-9]*\).*/\1/p' "$work/replay.log" | tail -n 1)
  "$profdata" merge -sparse "$work"/prof/*.profraw -o "$work/$t.profdata"
  mapfile -t files < <(cd "$root" && git ls-files | grep -E "${sources[$t]}" | grep -E '\.(c|cpp|h)$' | sed "s|^|$root/|")
  "$llvmcov" export -summary-only -instr-profile "$work/$t.profdata" "$bin" "${files[@]}" > "$work/summary.json"
  "$llvmcov" show -format=html -output-dir "$out/$t" -show-line-counts-or-regions \
    -instr-profile "$work/$t.profdata" "$bin" "${files[@]}"
  python3 - "$work/summary.json" "$t" "${inputs:-0}" > "$out/rows/$t.tsv" <<'EOF'
import json, sys
totals = json.load(open(sys.argv[1]))["data"][0]["totals"]
row = [sys.argv[2], sys.argv[3]]
for kind in ("lines", "functions", "regions", "branches"):
    row += [str(totals[kind]["covered"]), str(totals[kind]["count"])]
print("\t".join(row))
EOF
  cat "$out/rows/$t.tsv"
done
# The summary holds every target measured so far into this folder.
summary=$out/summary.tsv
{ printf 'target\tinputs\tlines\tlines_total\tfunctions\tfunctions_total\tregions\tregions_total\tbranches\tbranches_total\n'
  cat "$out"/rows/*.tsv; } > "$summary"

python3 - "$summary" "$out/index.html" <<'EOF'
import csv, html, sys
rows = list(csv.DictReader(open(sys.argv[1]), delimiter="\t"))
def cell(r, kind):
    n, total = int(r[kind]), int(r[kind + "_total"])
    return f"<td>{n:,} / {total:,} ({100.0 * n / total:.1f} %)</td>" if total else "<td>–</td>"
body = "".join(
    f"<tr><td><a href='{html.escape(r['target'])}/index.html'>{html.escape(r['target'])}</a></td>"
    f"<td>{int(r['inputs']):,}</td>" + "".join(cell(r, k) for k in ("lines", "functions", "regions", "branches")) + "</tr>"
    for r in rows)
open(sys.argv[2], "w").write(
    "<!doctype html><meta charset='utf-8'><title>blvd: fuzz corpus coverage</title>"
    "<style>body{font-family:sans-serif}td,th{padding:2px 10px;text-align:right}td:first-child{text-align:left}</style>"
    "<h1>Source coverage of the fuzz corpora</h1><p>Each target's corpus replayed once (tools/fuzz_coverage.sh), "
    "counted over the sources that target tests.</p><table><tr><th>target</th><th>inputs</th><th>lines</th>"
    f"<th>functions</th><th>regions</th><th>branches</th></tr>{body}</table>")
EOF
echo "wrote $out/index.html"
