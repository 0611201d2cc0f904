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
set +e  # a range CLI11 checks exits with its own code (105), before any work
msg=$("$blvd" bake --quiet "$osm" -o "$work/bad.blvd" --draco-level 11 2>&1); rc=$?
set -e
[ "$rc" != 0 ] && echo "$msg" | grep -q -- "--draco-level" && [ ! -e "$work/bad.blvd" ] || fail "--draco-level 11: rc $rc: $msg"

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

# --texture-codec webp: impostor atlases as lossy WebP (EXT_texture_webp), recorded in the meta,
# smaller than JPEG at the same quality, and drawn by the runtime with the far city no worse
# than 2 points of far_bad p50 from JPEG's along the same route.
# --impostor-codec meshopt: the same impostors (WebP) with their depth meshes in
# EXT_meshopt_compression instead of Draco, drawn the same.
for c in jpeg webp mo; do
  if [ $c = mo ]; then opts=(--impostor-codec meshopt); else opts=(--texture-codec $c); fi
  "$blvd" bake --quiet "$osm" -o "$work/tex-$c.blvd" --impostor layered --impostor-route auto:4 --seed 5 \
    "${opts[@]}" > "$work/tex-$c.txt"
  "$blvd" pack verify "$work/tex-$c.blvd" > /dev/null
  "$blvd" pack info "$work/tex-$c.blvd" --json > "$work/tex-$c.json"
  "$blvd" bench route "$work/tex-$c.blvd" --route auto:4 --seed 5 --size 400x240 --json "$work/route-$c.json" > /dev/null 2>&1
done
python3 - "$work" <<'PY'
import json, re, sys, os
w = sys.argv[1]
info = {c: json.load(open(os.path.join(w, f"tex-{c}.json"))) for c in ("jpeg", "webp")}
route = {c: json.load(open(os.path.join(w, f"route-{c}.json"))) for c in ("jpeg", "webp")}
bytes_ = {}
for c in ("jpeg", "webp"):
    assert info[c]["meta"]["impostors"]["texture_codec"] == c, info[c]["meta"]["impostors"]
    m = re.search(r"impostors \d+ meshes on \d+ cells, \d+ triangles, (\d+) bytes", open(os.path.join(w, f"tex-{c}.txt")).read())
    bytes_[c] = int(m.group(1))
assert 0 < bytes_["webp"] < bytes_["jpeg"], bytes_
fj, fw = (route[c]["modes"]["blvd"]["far_bad_p50"] for c in ("jpeg", "webp"))
assert (fj is None) == (fw is None), (fj, fw)  # the same poses are scored
assert route["webp"]["far_scored_poses"] == route["jpeg"]["far_scored_poses"] > 0, route["webp"]["far_scored_poses"]
if fj is not None:
    assert fw <= fj + 0.02, (fj, fw)
print("texture codecs: impostor bytes jpeg %d, webp %d; far_bad p50 %s, %s" % (bytes_["jpeg"], bytes_["webp"], fj, fw))
mo = json.load(open(os.path.join(w, "tex-mo.json")))
assert mo["meta"]["impostors"]["mesh_codec"] == "meshopt", mo["meta"]["impostors"]
assert info["webp"]["meta"]["impostors"]["mesh_codec"] == "draco", info["webp"]["meta"]["impostors"]
assert "KHR_draco_mesh_compression" not in open(os.path.join(w, "tex-mo.blvd"), "rb").read().decode("latin-1")
rm = json.load(open(os.path.join(w, "route-mo.json")))
assert rm["far_scored_poses"] == route["webp"]["far_scored_poses"], rm["far_scored_poses"]
fm = rm["modes"]["blvd"]["far_bad_p50"]
assert (fm is None) == (fw is None) and (fm is None or abs(fm - fw) <= 0.005), (fw, fm)
print("impostor mesh codecs: far_bad p50 draco %s, meshopt %s" % (fw, fm))
PY

# --block-codec and --draco-level: recorded in the package's meta. Draco level 0
# (fastest Draco decode) is bigger than the default 3; meshopt (the default) is
# bigger than Draco and plain bigger still. The four decode to the same meshes
# (`pack verify` decodes every blob; `bench decode` every mesh, side by side;
# its times are reported, not tested).
"$blvd" bake --quiet "$osm" -o "$work/mo.blvd" --impostor none --lod none > /dev/null
"$blvd" bake --quiet "$osm" -o "$work/cl3.blvd" --impostor none --lod none --block-codec draco > /dev/null
"$blvd" bake --quiet "$osm" -o "$work/cl0.blvd" --impostor none --lod none --block-codec draco --draco-level 0 > /dev/null
"$blvd" bake --quiet "$osm" -o "$work/plain.blvd" --impostor none --lod none --no-draco > /dev/null
for p in mo cl3 cl0 plain; do
  "$blvd" pack info "$work/$p.blvd" --json > "$work/$p.json"
  "$blvd" pack verify "$work/$p.blvd" > /dev/null
done
"$blvd" bench decode "$work/cl3.blvd" "$work/cl0.blvd" "$work/mo.blvd" "$work/plain.blvd" --json "$work/decode.json" > /dev/null
python3 - "$work/cl3.json" "$work/cl0.json" "$work/mo.json" "$work/plain.json" "$work/decode.json" <<'PY'
import json, sys
a, b, m, p, d = (json.load(open(f)) for f in sys.argv[1:6])
assert a["meta"]["draco_level"] == 3 and b["meta"]["draco_level"] == 0, (a["meta"], b["meta"])
assert [x["meta"]["block_codec"] for x in (a, b, m, p)] == ["draco", "draco", "meshopt", "plain"]
assert m["meta"]["draco"] is False and a["meta"]["draco"] is True
assert len(d) == 4 and d[0]["bytes"] < d[1]["bytes"] and d[1]["bytes_vs_first"] > 1, d
assert d[0]["bytes"] < d[2]["bytes"] < d[3]["bytes"], [x["bytes"] for x in d]
# Same blocks, triangle for triangle (the records' counts are what decoding gives).
assert all(x["lod_levels"] == a["lod_levels"] for x in (b, m, p)), [x["lod_levels"] for x in (a, b, m, p)]
assert all(x["blocks"]["meshes"] == a["lod_levels"][0]["blocks"] > 0 for x in d), (d, a["lod_levels"])
assert d[0]["impostors"]["meshes"] == 0, d
assert all(x["blocks"]["ms_total"] > 0 and x["blocks"]["ms_max"] >= x["blocks"]["ms_p50"] for x in d), d
print("block codec + draco level + bench decode: ok")
PY
set +e
"$blvd" bake --quiet "$osm" -o "$work/x.blvd" --block-codec zip > "$work/bad_codec.txt" 2>&1; rc=$?
set -e
[ "$rc" != 0 ] || { echo "bake with --block-codec zip succeeded"; exit 1; }
grep -q "block-codec" "$work/bad_codec.txt" || { cat "$work/bad_codec.txt"; exit 1; }
