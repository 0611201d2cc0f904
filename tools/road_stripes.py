#!/usr/bin/python3
"""Counts stripes of one road grey through the other in a drive's frames: the
pixels of a major road's grey with the minor roads' grey directly above and
below them, or the other way round (two coplanar street surfaces fighting in
the depth buffer, docs/decisions/0042).

    blvd view PKG --path auto:N --seed S --step M --mode full -o DIR
    tools/road_stripes.py DIR

The greys are the two street classes as the renderer lights them from above
(sdk/bake/block_mesh.cpp's colours under the default sun), within 3 levels.
Prints each frame with more than 50 such pixels, then the totals. Needs
Debian's python3-pil and python3-numpy.
"""
import glob
import os
import sys

import numpy as np
from PIL import Image

MAJOR = np.array([68, 70, 81])
MINOR = np.array([79, 81, 89])


def stripes(path):
    c = np.array(Image.open(path).convert("RGB")).astype(np.int64)
    a = np.abs(c - MAJOR).sum(-1) <= 3
    b = np.abs(c - MINOR).sum(-1) <= 3
    return int(((a[1:-1] & b[:-2] & b[2:]) | (b[1:-1] & a[:-2] & a[2:])).sum())


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    frames = sorted(f for f in glob.glob(os.path.join(sys.argv[1], "frame_*.png")) if not f.endswith("_full.png"))
    total = striped = 0
    for f in frames:
        k = stripes(f)
        total += k
        if k > 50:
            striped += 1
            print(f"{os.path.basename(f)}\t{k}")
    print(f"frames {len(frames)}, with more than 50 stripe pixels {striped}, stripe pixels {total}")


if __name__ == "__main__":
    main()
