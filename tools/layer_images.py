#!/usr/bin/python3
"""Writes impostor layer images of a package as raw RGBA8 files.

    tools/layer_images.py PACKAGE OUT_DIR [FIRST_CELL [CELL_STEP [IMAGES]]]

Extracts up to IMAGES (25) layer images with `blvd pack extract --cell C
--layer L` from cells FIRST_CELL, FIRST_CELL + CELL_STEP, ... (0, 5), decodes
each GLB's image with PIL (Debian's python3-pil) into OUT_DIR/imgN.rgba, and
prints "FILE WIDTH HEIGHT" for each, on one line: the arguments of
tools/etc2_compare.cpp and tools/texture_codecs.cpp. Needs build/sdk/cli/blvd.
"""
import io
import json
import struct
import subprocess
import sys

from PIL import Image

BLVD = "build/sdk/cli/blvd"


def images_of(glb):
    d = open(glb, "rb").read()
    length = struct.unpack("<I", d[12:16])[0]
    doc, binary = json.loads(d[20:20 + length]), 20 + length + 8
    for im in doc.get("images", []):
        view = doc["bufferViews"][im["bufferView"]]
        at = binary + view.get("byteOffset", 0)
        yield Image.open(io.BytesIO(d[at:at + view["byteLength"]])).convert("RGBA")


def main():
    pkg, out = sys.argv[1], sys.argv[2]
    first, step, want = (int(x) for x in (sys.argv[3:] + ["0", "5", "25"][len(sys.argv) - 3:])[:3])
    info = subprocess.run([BLVD, "pack", "info", "--json", pkg], check=True, capture_output=True).stdout
    cells = json.loads(info)["counts"]["cells"]
    args = []
    for cell in range(first, cells, step):
        for layer in range(64):
            glb = f"{out}/layer.glb"
            if subprocess.run([BLVD, "pack", "extract", pkg, "--cell", str(cell), "--layer", str(layer), "-o", glb],
                              capture_output=True).returncode != 0:
                break
            for rgba in images_of(glb):
                path = f"{out}/img{len(args) // 3}.rgba"
                open(path, "wb").write(rgba.tobytes())
                args += [path, str(rgba.size[0]), str(rgba.size[1])]
            if len(args) // 3 >= want:
                print(" ".join(args))
                return
    print(" ".join(args))


if __name__ == "__main__":
    main()
