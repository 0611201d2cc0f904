#!/usr/bin/env bash
# `blvd bake` options of the LOD chain and tiling: bad values fail before any
# work, naming the option; --lod none gives blocks with level 0 only.
# Usage: test_bake_options.sh BLVD_EXE OSM WORKDIR
set -euo pipefail
blvd=$1 osm=$2 work=$3
mkdir -p "$work"
fail() { echo "FAIL: $*" >&2; exit 1; }
bad() {  # bad OPTION VALUE EXPECTED_TEXT
  set +e
  msg=$("$blvd" bake --quiet "$osm" -o "$work/bad.blvd" "$1" "$2" 2>&1); rc=$?
  set -e
  [ "$rc" = 1 ] || fail "$1 $2 exited $rc: $msg"
  echo "$msg" | grep -q -- "$3" || fail "$1 $2: message does not say '$3': $msg"
  [ ! -e "$work/bad.blvd" ] || fail "$1 $2 wrote a package"
}
bad --tile 2y2 "--tile must be NxM"
bad --tile 0x3 "--tile must be NxM"
bad --lod-ratios 0.5,abc "'abc' is not a number"
bad --lod-ratios 0.5,0.6 "strictly decreasing"
bad --lod-ratios 0.5,0.4,0.3,0.2 "at most 3"

"$blvd" bake --quiet "$osm" -o "$work/none.blvd" --impostor none --lod none > /dev/null
"$blvd" pack info "$work/none.blvd" --json > "$work/none.json"
python3 - "$work/none.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
lv = j["lod_levels"]
assert lv[0]["blocks"] > 0 and all(lv[k]["blocks"] == 0 for k in (1, 2, 3)), lv
p = j["pool_sizing"]
assert p["max_block_triangles"] == p["max_block_lod0_triangles"] > 0, p
assert p["max_cell_impostor_layers"] == 0 and p["max_impostor_texture_bytes"] == 0, p
assert j["meta"]["lod"]["mode"] == "none", j["meta"]["lod"]
print("bake options: ok")
PY
