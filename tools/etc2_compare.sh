#!/usr/bin/env bash
# The ETC2 encoder of revision REV against the working tree's, on the impostor
# images of a package's cells (tools/etc2_compare.cpp):
#   tools/etc2_compare.sh REV PACKAGE [FIRST_CELL [CELL_STEP [IMAGES]]]
# Extracts up to IMAGES (25) layer images with `blvd pack extract --cell C
# --layer L` from cells FIRST_CELL, FIRST_CELL + CELL_STEP, ... (0, 5), decodes
# them to raw RGBA8 (Python's PIL), builds both encoders into one program
# (-O2) and runs it. Needs a built tree (build/sdk/cli/blvd).
set -euo pipefail
cd "$(dirname "$0")/.."
rev=${1:?usage: etc2_compare.sh REV PACKAGE [FIRST_CELL [CELL_STEP [IMAGES]]]}
pkg=${2:?usage: etc2_compare.sh REV PACKAGE [FIRST_CELL [CELL_STEP [IMAGES]]]}
first=${3:-0} step=${4:-5} want=${5:-25}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
git show "$rev:sdk/render/etc2.cpp" | sed 's/namespace blvd::render/namespace old_etc2/; s|"render/etc2.h"|"old_etc2.h"|' \
  > "$work/old_etc2.cpp"
git show "$rev:sdk/render/etc2.h" | sed 's/namespace blvd::render/namespace old_etc2/' > "$work/old_etc2.h"
g++ -O2 -std=c++17 -Isdk -I"$work" tools/etc2_compare.cpp "$work/old_etc2.cpp" sdk/render/etc2.cpp -o "$work/compare"
/usr/bin/python3 - "$pkg" "$first" "$step" "$want" "$work" > "$work/args" <<'PY'
import io, json, struct, subprocess, sys
from PIL import Image
pkg, first, step, want, work = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
cells = json.loads(subprocess.run(["build/sdk/cli/blvd", "pack", "info", "--json", pkg], check=True,
                                  capture_output=True).stdout)["counts"]["cells"]
args, n = [], 0
for cell in range(first, cells, step):
    for layer in range(64):
        glb = f"{work}/layer.glb"
        if subprocess.run(["build/sdk/cli/blvd", "pack", "extract", pkg, "--cell", str(cell), "--layer", str(layer),
                           "-o", glb], capture_output=True).returncode != 0:
            break
        d = open(glb, "rb").read()
        length = struct.unpack("<I", d[12:16])[0]
        doc, binary = json.loads(d[20:20 + length]), 20 + length + 8
        for im in doc.get("images", []):
            view = doc["bufferViews"][im["bufferView"]]
            at = binary + view.get("byteOffset", 0)
            rgba = Image.open(io.BytesIO(d[at:at + view["byteLength"]])).convert("RGBA")
            path = f"{work}/img{n}.rgba"
            open(path, "wb").write(rgba.tobytes())
            args += [path, str(rgba.size[0]), str(rgba.size[1])]
            n += 1
        if n >= want:
            break
    if n >= want:
        break
print(" ".join(args))
PY
# shellcheck disable=SC2046
"$work/compare" $(cat "$work/args")
