"""Host-side assertions of tests/vcan on what the guest sent back.

Each check returns a short summary dict and raises CheckError with a message
that names the file, the index and the values that differ."""
import csv
import json
import math


class CheckError(Exception):
    pass


def read_candump(path, iface=None):
    """[(t, iface, 'ID#DATA')] of a candump -l/-L log; only `iface` when given."""
    out = []
    with open(path) as f:
        for n, line in enumerate(f, 1):
            parts = line.split()
            if not parts:
                continue
            if len(parts) < 3 or not parts[0].startswith("("):
                raise CheckError("%s:%d: not a candump line: %r" % (path, n, line.strip()))
            if iface is None or parts[1] == iface:
                out.append((float(parts[0][1:-1]), parts[1], parts[2]))
    return out


def same_frames(sent, captured):
    """The capture holds exactly the replayed frames (ids and payloads), in order."""
    if not captured:
        raise CheckError("candump captured no frames on vcan0")
    for i, (a, b) in enumerate(zip(sent, captured)):
        if a[2] != b[2]:
            raise CheckError("frame %d differs: replayed %s, captured %s (t %.6f in the trace)" % (i, a[2], b[2], a[0]))
    if len(sent) != len(captured):
        raise CheckError("replayed %d frames, candump captured %d (the first %d agree)" %
                         (len(sent), len(captured), min(len(sent), len(captured))))
    return {"frames": len(sent)}


def read_jsonl(path):
    with open(path) as f:
        return [json.loads(line) for line in f if line.strip()]


def _reference(reference_csv):
    with open(reference_csv) as f:
        return [(float(r["t_boot_s"]), float(r["speed_mps"])) for r in csv.DictReader(f)]


def _samples(odometry, frame_id, expected):
    got = [o for o in odometry if o["id"] == frame_id]
    if len(got) != expected:
        raise CheckError("%d decoded samples of frame 0x%X, expected %d" % (len(got), frame_id, expected))
    return got


def speed_matches_reference(odometry, reference_csv, frame_id, tol_mps):
    """Every `frame_id` (0xAA, WHEEL_SPEEDS) sample's speed equals the reference
    CSV row of the same index (the CSV has one row per such frame) within tol_mps."""
    ref = _reference(reference_csv)
    got = _samples(odometry, frame_id, len(ref))
    worst = 0.0
    for i, (o, (rt, rv)) in enumerate(zip(got, ref)):
        dv = abs(o["speed"] - rv)
        if not dv <= tol_mps:
            raise CheckError("sample %d (reference t %.6f): speed %.9g, reference %.6f (|diff| %.3g > %g)" %
                             (i, rt, o["speed"], rv, dv, tol_mps))
        worst = max(worst, dv)
    return {"samples": len(got), "max_speed_diff_mps": worst}


def times_match_bus(odometry, bus, tol_s):
    """Every odometry sample is stamped with the time its frame (same id) has on
    the bus log (`bus`: read_candump of candump's capture, or of the trace
    itself), in order: the tracker was fed at each frame's own time. Kernel
    timestamps are shared by every socket; candump prints them truncated to
    microseconds, hence tol_s."""
    if not odometry:
        raise CheckError("no odometry samples were decoded")
    by_id = {}
    for f in bus:
        by_id.setdefault(int(f[2].split("#", 1)[0], 16), []).append(f[0])
    pos, worst = {}, 0.0
    for i, o in enumerate(odometry):
        times = by_id.get(o["id"], [])
        j = pos.get(o["id"], 0)
        while j < len(times) and times[j] < o["t"] - tol_s:
            j += 1
        if j == len(times) or abs(times[j] - o["t"]) > tol_s:
            raise CheckError("odometry sample %d (frame 0x%X) is stamped %.6f; no such frame on the bus at that time "
                             "(next one at %s)" % (i, o["id"], o["t"], "%.6f" % times[j] if j < len(times) else "none"))
        worst = max(worst, abs(times[j] - o["t"]))
        pos[o["id"]] = j + 1
    return {"samples": len(odometry), "max_diff_s": worst}


def paced_like_reference(odometry, reference_csv, frame_id, median_tol_s, max_tol_s):
    """The replay ran in real time: each sample's time minus its reference time
    is the same constant (the clocks' offset, taken as the median) up to
    jitter. A TCG guest on a loaded host stalls now and then, so the median
    deviation is held tight and the worst one loosely."""
    ref = _reference(reference_csv)
    got = _samples(odometry, frame_id, len(ref))
    off = sorted(o["t"] - rt for o, (rt, _) in zip(got, ref))
    centre = off[len(off) // 2]
    d = sorted(abs(x - centre) for x in off)
    median, worst = d[len(d) // 2], d[-1]
    if median > median_tol_s or worst > max_tol_s:
        raise CheckError("replay timing against the reference: median deviation %.3f s (limit %g), worst %.3f s (limit %g)" %
                         (median, median_tol_s, worst, max_tol_s))
    return {"median_s": median, "max_s": worst}


def distance_matches_reference(poses, reference_csv, tol_frac):
    """The dead-reckoned path length of the valid poses equals the integral of
    the reference speed over the same span within tol_frac."""
    valid = [p for p in poses if p["flags"] & 1]
    if len(valid) < 2:
        raise CheckError("%d valid poses; dead reckoning needs --start" % len(valid))
    path = sum(math.hypot(b["x"] - a["x"], b["y"] - a["y"]) for a, b in zip(valid, valid[1:]))
    ref = _reference(reference_csv)
    span = valid[-1]["t"] - valid[0]["t"]
    t0 = ref[0][0]
    integral = sum(0.5 * (a[1] + b[1]) * (b[0] - a[0]) for a, b in zip(ref, ref[1:]) if b[0] - t0 <= span)
    if integral <= 0 or abs(path - integral) > tol_frac * integral:
        raise CheckError("dead-reckoned path %.1f m over %.1f s, the reference speed integrates to %.1f m (tolerance %.1f %%)" %
                         (path, span, integral, 100 * tol_frac))
    return {"path_m": path, "reference_m": integral}


def read_cells(path):
    """An expected-cells file: one cell id per line, in visiting order; '#' comments."""
    cells = []
    with open(path) as f:
        for line in f:
            line = line.split("#", 1)[0].strip()
            if line:
                cells.append(int(line))
    return cells


def cells_match(poses, expected, settle_s):
    """The matched cells after the first settle_s seconds, consecutive repeats
    collapsed, equal the expected sequence from the cell where they start."""
    if not poses:
        raise CheckError("no poses")
    t0 = poses[0]["t"]
    seen = []
    for p in poses:
        if p["t"] - t0 < settle_s or not (p["flags"] & 4) or p["cell"] < 0:
            continue
        if not seen or seen[-1] != p["cell"]:
            seen.append(p["cell"])
    if not seen:
        raise CheckError("no matched pose after the first %g s" % settle_s)
    if seen[0] not in expected:
        raise CheckError("first matched cell %d (after %g s) is not in the expected sequence" % (seen[0], settle_s))
    want = expected[expected.index(seen[0]):]
    for i, (a, b) in enumerate(zip(seen, want)):
        if a != b:
            raise CheckError("cell %d of the sequence: matched %d, expected %d (matched %s..., expected %s...)" %
                             (i, a, b, seen[max(0, i - 3):i + 3], want[max(0, i - 3):i + 3]))
    if len(seen) != len(want):
        raise CheckError("matched %d cells after %g s, expected %d from cell %d" % (len(seen), settle_s, len(want), seen[0]))
    return {"cells": len(seen)}
