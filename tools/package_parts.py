#!/usr/bin/python3
"""Counts where a package's blob bytes go: block levels and impostor layers,
stored and as contents, and of the contents the images and the glTF JSON.

    tools/package_parts.py PACKAGE [STEP]

Reads BIDX (docs/package-format.md) from `blvd pack info`'s section table,
decompresses each STEP-th blob (1) with the zstd tool (the built-in
dictionary taken from sdk/package/blob_dictionary.cpp where BIDX says so),
and prints the sums scaled by STEP. A GLB with an image is an impostor
layer. Needs build/sdk/cli/blvd and zstd.
"""
import json
import os
import re
import struct
import subprocess
import sys
import tempfile

BLVD = "build/sdk/cli/blvd"
ZSTD, DICT = 1, 2


def dictionary_file():
    text = open("sdk/package/blob_dictionary.cpp").read()
    body = text[text.index("kDictionary[] ="):text.index(";", text.index("kDictionary[] ="))]
    raw = "".join(json.loads(s) for s in re.findall(r'"(?:[^"\\]|\\.)*"', body))
    f = tempfile.NamedTemporaryFile(delete=False)
    f.write(raw.encode())
    f.close()
    return f.name


def blob_index(pkg):
    info = subprocess.run([BLVD, "pack", "info", pkg], check=True, capture_output=True, text=True).stdout
    at = next(int(l.split()[2]) for l in info.splitlines() if l.split()[:1] == ["BIDX"])
    f = open(pkg, "rb")
    f.seek(at)
    count, size = struct.unpack("<II", f.read(8))
    return f, [struct.unpack("<QQIIQ", f.read(size)[:32]) for _ in range(count)]


def main():
    pkg, step = sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 1
    d = dictionary_file()
    f, entries = blob_index(pkg)
    sums = {}
    for i in range(0, len(entries), step):
        offset, size, _, flags, _ = entries[i]
        f.seek(offset)
        b = f.read(size)
        if flags & ZSTD:
            b = subprocess.run(["zstd", "-dc"] + (["-D", d] if flags & DICT else []), input=b, check=True,
                               capture_output=True).stdout
        if b[:4] != b"glTF":
            kind, length, doc = "other", 0, {}
        else:
            length = struct.unpack("<I", b[12:16])[0]
            doc = json.loads(b[20:20 + length])
            kind = "impostor layers" if doc.get("images") else "block levels"
        for key, value in (("count", 1), ("stored", size), ("contents", len(b)), ("json", length),
                           ("images", sum(doc["bufferViews"][im["bufferView"]]["byteLength"]
                                          for im in doc.get("images", [])))):
            sums[(kind, key)] = sums.get((kind, key), 0) + value * step
    os.unlink(d)
    for (kind, key), value in sorted(sums.items()):
        print(f"{kind:16} {key:9} {value:>12,}")


if __name__ == "__main__":
    main()
