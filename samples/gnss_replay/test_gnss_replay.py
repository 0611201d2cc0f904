#!/usr/bin/env python3
"""samples.gnss_replay: gnss_replay on a sim_feed Monaco drive (NMEA + truth CSV).

Checks that the frames exist and are not blank (luminance variance of every
PNG, decoded here), that the matched cells follow the truth's cell sequence
after the first seconds (tests/vcan/checks.py), and that bad input fails with
a message naming the file and line."""
import argparse
import csv
import hashlib
import json
import os
import shutil
import struct
import subprocess
import sys
import zlib


def fail(msg):
    print("FAIL: " + msg, file=sys.stderr)
    sys.exit(1)


def png_rgba(path):
    """(width, height, rows of RGBA bytes) of an 8-bit RGBA PNG (what stb writes)."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        fail("%s: not a PNG" % path)
    pos, idat, w = 8, b"", 0
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, colour = struct.unpack(">IIBB", body[:10])
            if (depth, colour) != (8, 6):
                fail("%s: not 8-bit RGBA (depth %d, colour type %d)" % (path, depth, colour))
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw, stride, rows, prev = zlib.decompress(idat), w * 4, [], bytearray(w * 4)
    for y in range(h):
        ftype, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - 4] if i >= 4 else 0
            b = prev[i]
            c = prev[i - 4] if i >= 4 else 0
            if ftype == 1:
                line[i] = (line[i] + a) & 255
            elif ftype == 2:
                line[i] = (line[i] + b) & 255
            elif ftype == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif ftype == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line)
        prev = line
    return w, h, rows


def luminance_variance(path):
    _, _, rows = png_rgba(path)
    lum = [(2126 * r[i] + 7152 * r[i + 1] + 722 * r[i + 2]) / 10000.0 for r in rows for i in range(0, len(r), 4)]
    mean = sum(lum) / len(lum)
    return sum((v - mean) ** 2 for v in lum) / len(lum)


def truth_cells(path):
    """The truth's cell sequence, consecutive repeats collapsed."""
    seq = []
    with open(path) as f:
        for row in csv.DictReader(f):
            c = int(row["cell"])
            if c != 0xFFFFFFFF and (not seq or seq[-1] != c):
                seq.append(c)
    return seq


def run(exe, args, want_rc, what):
    p = subprocess.run([exe] + args, capture_output=True, text=True, timeout=240)
    if (want_rc == 0) != (p.returncode == 0) or (want_rc and p.returncode != want_rc):
        fail("%s: exit %d, expected %d\nstderr:\n%s" % (what, p.returncode, want_rc, p.stderr))
    return p.stderr


def expect_in(text, needle, what):
    if needle not in text:
        fail("%s: %r not in the output:\n%s" % (what, needle, text))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--exe", required=True)
    ap.add_argument("--package", required=True)
    ap.add_argument("--trace", required=True, help="sim_feed output prefix: TRACE.nmea, TRACE.csv")
    ap.add_argument("--checks", required=True, help="folder of tests/vcan/checks.py")
    ap.add_argument("--work", required=True)
    ap.add_argument("--settle", type=float, default=5.0, help="seconds before the cells must follow the truth")
    a = ap.parse_args()
    sys.path.insert(0, a.checks)
    import checks  # tests/vcan/checks.py: cells_match, read_jsonl

    shutil.rmtree(a.work, ignore_errors=True)
    os.makedirs(a.work)
    nmea = a.trace + ".nmea"
    frames, poses, stats_path = (os.path.join(a.work, n) for n in ("frames", "poses.jsonl", "stats.json"))

    # The drive: frames at 2 fps of log time (small: this script decodes every one), poses every 0.1 s.
    run(a.exe, [nmea, "--package", a.package, "--fps", "2", "--width", "160", "--height", "96", "--frames", frames,
                "--poses", poses, "--stats", stats_path], 0, "replay")
    with open(stats_path) as f:
        stats = json.load(f)
    pngs = sorted(n for n in os.listdir(frames) if n.endswith(".png"))
    log_s = stats["last_t"] - stats["first_t"]
    if stats["malformed_lines"] != 0 or stats["position_fixes"] == 0:
        fail("the clean trace: %d malformed lines, %d position fixes" % (stats["malformed_lines"],
                                                                        stats["position_fixes"]))
    if len(pngs) != stats["png_written"] or len(pngs) < int(log_s * 2):
        fail("%d PNGs for %.1f s of log at 2 fps (stats: %d written)" % (len(pngs), log_s, stats["png_written"]))
    variances = [luminance_variance(os.path.join(frames, n)) for n in pngs]
    flat = [n for n, v in zip(pngs, variances) if v < 20.0]
    if flat:
        fail("%d of %d frames nearly blank (luminance variance < 20): %s" % (len(flat), len(pngs), flat[:5]))
    digests = {}
    for n in pngs:
        digests.setdefault(hashlib.sha1(open(os.path.join(frames, n), "rb").read()).digest(), []).append(n)
    distinct = len(digests)
    if distinct != len(pngs):
        repeats = [names for names in digests.values() if len(names) > 1]
        fail("%d distinct frames of %d: the view stood still between %s" % (distinct, len(pngs), repeats[:3]))
    pose_lines = checks.read_jsonl(poses)
    if len(pose_lines) != stats["poses"]:
        fail("%d pose lines, stats say %d" % (len(pose_lines), stats["poses"]))
    expected = truth_cells(a.trace + ".csv")
    got = checks.cells_match(pose_lines, expected, a.settle)
    print("replay: %d frames (%d distinct, luminance variance %.0f..%.0f), %d poses, %d cells after %g s match the truth; "
          "frame ms p50 %.2f p95 %.2f; %d degraded" %
          (len(pngs), distinct, min(variances), max(variances), len(pose_lines), got["cells"], a.settle,
           stats["frame_ms_p50"], stats["frame_ms_p95"], stats["degraded_frames"]))

    with open(nmea) as f:
        lines = f.read().splitlines(True)
    # One corrupted sentence (its checksum no longer matches) at line 40.
    bad = os.path.join(a.work, "corrupt.nmea")
    corrupt = list(lines)
    corrupt[39] = corrupt[39].replace(",", ";", 1)
    with open(bad, "w") as f:
        f.writelines(corrupt)
    err = run(a.exe, [bad, "--package", a.package, "--strict", "--duration", "20"], 1, "--strict, corrupt line")
    expect_in(err, bad + ":40:", "--strict, corrupt line")
    bad_stats = os.path.join(a.work, "corrupt-stats.json")
    err = run(a.exe, [bad, "--package", a.package, "--duration", "20", "--stats", bad_stats], 0, "corrupt line")
    expect_in(err, bad + ":40:", "corrupt line, skipped")
    with open(bad_stats) as f:
        if json.load(f)["malformed_lines"] != 1:
            fail("corrupt line: malformed_lines is not 1 in %s" % bad_stats)

    # No fix at all: garbage and one broken sentence.
    nofix = os.path.join(a.work, "nofix.nmea")
    with open(nofix, "w") as f:
        f.write("hello\n" + lines[0].replace(",", ";", 1))
    err = run(a.exe, [nofix, "--package", a.package], 1, "no fix")
    expect_in(err, "no position fix", "no fix")
    expect_in(err, nofix + ":2:", "no fix")

    # Files that cannot be read.
    missing = os.path.join(a.work, "missing.nmea")
    expect_in(run(a.exe, [missing, "--package", a.package], 2, "missing log"), missing, "missing log")
    expect_in(run(a.exe, [nmea, "--package", nmea], 2, "not a package"), "package " + nmea, "not a package")
    print("bad input: corrupt line named (strict: exit 1; else skipped and counted), no fix, missing log, "
          "not a package: all reported")


if __name__ == "__main__":
    main()
