#!/usr/bin/env bash
# Downtown San Francisco end to end, the dense and tall city: bake with
# impostors on a short route, verify, drive it to frames, and measure the far
# city along it. The extract's towers are building:part outlines with heights
# and min_height, its courtyards multipolygons with many inner rings, and its
# footways and service lanes are not streets.
# Usage: test_sf_end_to_end.sh BLVD_EXE OSM WORKDIR
set -euo pipefail
blvd=$1 osm=$2 work=$3
rm -rf "$work" && mkdir -p "$work"
"$blvd" bake --quiet "$osm" -o "$work/sf.blvd" --impostor both --impostor-route auto:6 --seed 1 > "$work/bake.txt"
"$blvd" pack verify "$work/sf.blvd" > /dev/null
"$blvd" pack info "$work/sf.blvd" --json > "$work/info.json"
"$blvd" view "$work/sf.blvd" --path auto:6 --seed 1 --step 20 --with-full -o "$work/drive" > /dev/null
"$blvd" bench route "$work/sf.blvd" --route auto:6 --seed 1 --json "$work/route.json" --html "$work/route_html" \
  > /dev/null 2>&1
PYTHONPATH="$(dirname "$0")" python3 - "$work" "$blvd" <<'PY'
import glob, hashlib, json, os, re, shlex, subprocess, sys

import png_rgba

# The same pose draws the same frame: 0 pixels differ (45-51 of 384,000 when the command
# gave the heading to 0.1 deg and lat/lon to 1e-7 deg); a few are left for rounding ties.
REPRO_MAX_SHARE = 2e-5
work = sys.argv[1]
info = json.load(open(os.path.join(work, "info.json")))
c, m = info["counts"], info["meta"]["counts"]
# What the extract holds (../shared/data/SOURCES.md): 7,823 buildings and 846 parts, about
# 6,300 with a height or levels; a parts' outline is hidden by its parts.
assert 8000 <= c["buildings"] <= 8700, c
assert m["height_tagged"] + m["level_tagged"] >= 6000, m
assert m["skipped"] == 0, m
# The drivable grid, not the footways: about 3,000 of the 8,553 highway ways.
assert 2500 <= m["streets"] <= 3500, m
assert c["cells"] > 7000 and c["blocks"] > 1000, c
route = info["meta"]["impostor_route"]
assert len(route) == 6, route
frames = sorted(glob.glob(os.path.join(work, "drive", "*.png")))
assert len(frames) >= 12, frames  # blvd and full frames of every pose
digests = {hashlib.sha256(open(f, "rb").read()).hexdigest() for f in frames}
assert len(digests) == len(frames), "two frames of the drive are the same image"
r = json.load(open(os.path.join(work, "route.json")))
assert r["far_scored_poses"] >= 1, r["far_scored_poses"]
blvd, local = r["modes"]["blvd"], r["modes"]["local"]
# The impostors stand for the far city: far less of it is wrong than with the local model alone.
assert blvd["far_bad_p50"] < 0.5 * local["far_bad_p50"], (blvd["far_bad_p50"], local["far_bad_p50"])
assert blvd["triangles_p50"] < r["modes"]["full"]["triangles_p50"], blvd
# Each worst frame's caption is the `blvd view` command that draws it again: run the first
# one's full and blvd commands and compare their frames with the gallery's, pixel by pixel.
html = open(os.path.join(work, "route_html", "index.html")).read()
g = re.search(r"pose (\d+), cell \d+: (blvd view [^<]*?-o full\.png)</figcaption>.*?"
              r"<figcaption>(blvd view [^<]*?-o blvd\.png)</figcaption>", html, re.S)
assert g, "the worst-frames gallery names no blvd view command"
pose = g.group(1)
for cmd in g.group(2, 3):
    args = shlex.split(cmd)
    mode = args[args.index("--mode") + 1]
    out = os.path.join(work, "repro-%s.png" % mode)
    subprocess.run([sys.argv[2]] + args[1:-2] + ["-o", out], check=True, stdout=subprocess.DEVNULL)
    w, h, a = png_rgba.read(out)
    w2, h2, b = png_rgba.read(os.path.join(work, "route_html", "frames", "worst%04d_%s.png" % (int(pose), mode)))
    assert (w, h) == (w2, h2), ((w, h), (w2, h2))
    off = sum(1 for ra, rb in zip(a, b) for i in range(0, 4 * w, 4) if max(abs(ra[i + k] - rb[i + k]) for k in range(3)) > 25)
    assert off <= REPRO_MAX_SHARE * w * h, "%s: %d of %d pixels differ from the gallery's frame" % (cmd, off, w * h)
print("sf end to end: %d buildings, %d cells, %d frames, blvd far_bad p50 %.3f (local %.3f)"
      % (c["buildings"], c["cells"], len(frames), blvd["far_bad_p50"], local["far_bad_p50"]))
PY
