#!/usr/bin/env bash
# The `blvd` tool end to end on the baked Monaco package: pack info/verify/
# extract, and a corrupted copy that verify must reject naming the offset.
# Usage: test_cli.sh BLVD_EXE PACKAGE WORKDIR
set -euo pipefail
blvd=$1 pkg=$2 work=$3
mkdir -p "$work"
fail() { echo "FAIL: $*" >&2; exit 1; }

"$blvd" pack info "$pkg" | grep "junctions" > /dev/null || fail "pack info"
"$blvd" pack info "$pkg" --json > "$work/info.json"
python3 - "$work/info.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
c = j["counts"]
assert c["junctions"] > 100 and c["cells"] > 200 and c["blocks"] > 50, c
assert c["buildings"] > 1000 and c["triangles"] > 10000, c
for s in ("GRPH", "CELL", "BLCK", "META", "BIDX", "BDAT"):
    assert s in j["sections"] and j["sections"][s]["bytes"] > 0, s
# Levels of detail: fewer triangles per level, errors growing; pool sizing filled in.
lv = j["lod_levels"]
assert 0 < lv[0]["blocks"] <= c["blocks"], lv
assert lv[1]["blocks"] > 0 and lv[1]["triangles"] < lv[0]["triangles"], lv
assert all(lv[k]["max_error_m"] >= 0 for k in range(4)), lv
p = j["pool_sizing"]
assert p["max_block_triangles"] >= p["max_block_lod0_triangles"] > 0, p
assert p["max_cell_local_blocks"] > 0 and p["max_cell_impostor_layers"] > 0, p
PY
"$blvd" pack verify "$pkg" | grep "ok" > /dev/null || fail "verify of a good package"

# Flip one byte in the middle of the blob data: verify exits 1 naming a blob offset.
cp "$pkg" "$work/bad.blvd"
size=$(stat -c %s "$work/bad.blvd")
python3 - "$work/bad.blvd" <<'PY'
import sys
p = sys.argv[1]
b = bytearray(open(p, "rb").read())
b[len(b) * 2 // 3] ^= 0x5A
open(p, "wb").write(b)
PY
set +e
msg=$("$blvd" pack verify "$work/bad.blvd" 2>&1); rc=$?
set -e
[ "$rc" = 1 ] || fail "verify of a corrupt package exited $rc: $msg"
echo "$msg" | grep -q "offset" || fail "verify message names no offset: $msg"
echo "$msg" | grep -q "bad.blvd" || fail "verify message names no file: $msg"

# Truncated package: every command fails cleanly.
head -c $((size / 2)) "$pkg" > "$work/cut.blvd"
set +e
"$blvd" pack info "$work/cut.blvd" > /dev/null 2>&1; rc=$?
set -e
[ "$rc" = 1 ] || fail "pack info on a truncated package exited $rc"

# Extract: a block and a cell's local model are valid GLBs (magic, version 2, length).
"$blvd" pack extract "$pkg" --block 1 -o "$work/block1.glb"
"$blvd" pack extract "$pkg" --cell 0 -o "$work/cell0.glb"
for f in "$work/block1.glb" "$work/cell0.glb"; do
python3 - "$f" <<'PY'
import struct, sys, json
b = open(sys.argv[1], "rb").read()
magic, ver, length = struct.unpack_from("<4sII", b)
assert magic == b"glTF" and ver == 2 and length == len(b), (magic, ver, length)
clen, ctype = struct.unpack_from("<I4s", b, 12)
assert ctype == b"JSON"
j = json.loads(b[20:20 + clen])
assert j["asset"]["version"] == "2.0" and j["meshes"], j.keys()
prim = j["meshes"][0]["primitives"][0]
if "block" in sys.argv[1]:  # block levels: EXT_meshopt_compression (the default bake), every view compressed
    assert j["extensionsRequired"] == ["EXT_meshopt_compression", "KHR_mesh_quantization"], j["extensionsRequired"]
    assert all("EXT_meshopt_compression" in v["extensions"] for v in j["bufferViews"]), j["bufferViews"]
    assert j["buffers"][1]["extensions"]["EXT_meshopt_compression"]["fallback"] is True, j["buffers"]
else:  # a cell's merged local model: Draco, as `pack extract` writes it
    assert "KHR_draco_mesh_compression" in j.get("extensionsRequired", []), "cells must be Draco-compressed"
    assert "KHR_draco_mesh_compression" in prim["extensions"], prim
if "block" in sys.argv[1]:  # a block holds its levels of detail (MSFT_lod, not required)
    assert "MSFT_lod" in j["extensionsUsed"] and "MSFT_lod" not in j["extensionsRequired"], j["extensionsUsed"]
    ids = j["nodes"][0]["extensions"]["MSFT_lod"]["ids"]
    assert len(ids) >= 1 and j["scenes"][0]["nodes"] == [0], ids
PY
done
# view: one pose to PNG.
"$blvd" view "$pkg" --lat 43.735370 --lon 7.417288 --heading 211 --size 320x200 -o "$work/view.png"
python3 - "$work/view.png" <<'PY'
import struct, sys
b = open(sys.argv[1], "rb").read()
assert b[:8] == b"\x89PNG\r\n\x1a\n"
w, h = struct.unpack(">II", b[16:24])
assert (w, h) == (320, 200), (w, h)
PY
# view --items: the pose's object ids as a PNG, each a block of the package
# or an impostor layer (BLVD_ITEM_IMPOSTOR | k).
"$blvd" view "$pkg" --lat 43.735370 --lon 7.417288 --heading 211 --size 320x200 -o "$work/view2.png" \
  --items "$work/items.png" > /dev/null
blocks=$("$blvd" pack info "$pkg" --json | python3 -c 'import json,sys; print(json.load(sys.stdin)["counts"]["blocks"])')
PYTHONPATH="$(dirname "$0")" python3 - "$work/items.png" "$blocks" <<'PY'
import sys
import png_rgba
w, h, rows = png_rgba.read(sys.argv[1])
assert (w, h) == (320, 200), (w, h)
ids = {(r[4 * x] | r[4 * x + 1] << 8 | r[4 * x + 2] << 16) if r[4 * x + 3] else 0 for r in rows for x in range(w)}
blocks = [i for i in ids if i and not i & 0x800000]
layers = [i & 0x7FFFFF for i in ids if i & 0x800000]
assert blocks and all(i <= int(sys.argv[2]) for i in blocks), sorted(ids)
assert all(k >= 1 for k in layers), layers
PY
# view: a pose 700 km from the package is refused, naming it, and writes no frame.
set +e
err=$("$blvd" view "$pkg" --lat 50 --lon 7.4246 --heading 304 --size 160x96 -o "$work/far.png" 2>&1); rc=$?
set -e
[ "$rc" != 0 ] && grep -q "off the map: lat 50.000000, lon 7.424600 lies [0-9]* km outside" <<< "$err" ||
  fail "view off the map: rc $rc: $err"
[ ! -e "$work/far.png" ] || fail "view off the map wrote a frame"
# pack cell: one cell as JSON; a cell that does not exist is named.
"$blvd" pack cell "$pkg" 0 | python3 -c 'import json,sys; j=json.load(sys.stdin); assert j["cell"] == 0 and "local_blocks" in j and j["length_m"] > 0, j'
set +e
err=$("$blvd" pack cell "$pkg" 99999999 2>&1); rc=$?
set -e
[ "$rc" != 0 ] && grep -q "cell 99999999 does not exist" <<< "$err" || fail "pack cell of a missing cell: $err"
# view: a drive with the full model beside each frame; the page flips between them.
"$blvd" view "$pkg" --path auto:2 --seed 7 --step 20 --size 160x96 --with-full -o "$work/drive" > /dev/null
[ -f "$work/drive/frame_0000.png" ] && [ -f "$work/drive/frame_0000_full.png" ] || fail "view --with-full wrote no full-model frame"
n_frames=$(ls "$work/drive" | grep -c '^frame_[0-9]*\.png$')
[ "$(grep -c 'data-full="frame_' "$work/drive/index.html")" = "$n_frames" ] || fail "index.html does not flip every frame"
# pack extract --layer: a cell's impostor layer as a plain GLB with its texture.
# The drive above starts the package's impostor route (auto:40, seed 7).
cell=$(grep -o 'cell [0-9]*' "$work/drive/index.html" | head -1 | cut -d' ' -f2)
"$blvd" pack cell "$pkg" "$cell" | python3 -c 'import json,sys; assert json.load(sys.stdin)["layered"]' ||
  fail "cell $cell of the impostor route has no layers"
"$blvd" pack extract "$pkg" --cell "$cell" --layer 0 -o "$work/layer0.glb" > /dev/null
python3 - "$work/layer0.glb" <<'PY'
import json, struct, sys
b = open(sys.argv[1], "rb").read()
clen, = struct.unpack_from("<I", b, 12)
j = json.loads(b[20:20 + clen])
prim = j["meshes"][0]["primitives"][0]
assert "extensionsRequired" not in j or not any("compression" in e for e in j["extensionsRequired"]), j
assert "TEXCOORD_0" in prim["attributes"] and j["accessors"][prim["indices"]]["count"] >= 3, prim
assert j["images"][0]["mimeType"] in ("image/webp", "image/jpeg"), j["images"]
PY
set +e
err=$("$blvd" pack extract "$pkg" --cell "$cell" --layer 999 -o "$work/x.glb" 2>&1); rc=$?
set -e
[ "$rc" != 0 ] && grep -q "layered impostor layers, not 999" <<< "$err" || fail "extract of a missing layer: $err"
set +e
"$blvd" view "$pkg" --lat 43.7 --size 12x3 -o "$work/x.png" > /dev/null 2>&1; rc=$?
set -e
[ "$rc" != 0 ] || fail "view with a bad --size succeeded"
echo "cli: all checks passed"
