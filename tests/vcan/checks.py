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


def truth_cells(truth_csv):
    """The cells sim_feed's ground-truth CSV visits, in order, consecutive
    repeats collapsed (what its truth JSON lists as "cells")."""
    cells = []
    with open(truth_csv) as f:
        for row in csv.DictReader(f):
            c = int(row["cell"])
            if not cells or cells[-1] != c:
                cells.append(c)
    if not cells:
        raise CheckError("%s has no rows" % truth_csv)
    return cells


def matched_runs(poses, settle_s=0):
    """[(cell, t_first, t_next)] of the matched poses after the first settle_s
    seconds, consecutive repeats collapsed; t_next is when the next run starts
    (the last pose's time for the last run)."""
    if not poses:
        raise CheckError("no poses")
    t0, runs = poses[0]["t"], []
    for p in poses:
        if p["t"] - t0 < settle_s or not (p["flags"] & 4) or p["cell"] < 0:
            continue
        if runs and runs[-1][0] == p["cell"]:
            continue
        if runs:
            runs[-1][2] = p["t"]
        runs.append([p["cell"], p["t"], p["t"]])
    if runs:
        runs[-1][2] = poses[-1]["t"]
    return [tuple(r) for r in runs]


def visited_equals_poses(cells_visited, poses):
    """The stats' cells_visited is the poses' matched cell sequence (repeats collapsed)."""
    seq = [r[0] for r in matched_runs(poses)]
    if cells_visited != seq:
        i = next((k for k, (a, b) in enumerate(zip(cells_visited, seq)) if a != b), min(len(seq), len(cells_visited)))
        raise CheckError("cells_visited differs from the poses' matched cells at entry %d: %s... vs %s..." %
                         (i, cells_visited[i:i + 3], seq[i:i + 3]))
    return {"cells": len(seq)}


def cells_follow_route(poses, route, settle_s, max_detour_s, max_backwards, min_coverage):
    """The matched cells follow the route. From the first matched cell on the
    route after settle_s (the tracker converges before that): no stretch off
    the route lasts longer than max_detour_s (at a junction the matcher may
    hold a neighbouring cell for a moment), at most max_backwards steps go back
    along it, at least min_coverage of the route's cells from there on were
    matched, and the last route cell was."""
    index = {}
    for i, c in enumerate(route):
        index.setdefault(c, i)
    runs = matched_runs(poses, settle_s)
    start = next((k for k, r in enumerate(runs) if r[0] in index), None)
    if start is None:
        raise CheckError("none of the %d cells matched after %g s is on the route (%s...)" %
                         (len(runs), settle_s, [r[0] for r in runs[:5]]))
    detours, back, last, seen = [], [], index[runs[start][0]], set()
    for cell, t, t_next in runs[start:]:
        if cell not in index:
            detours.append((cell, t - poses[0]["t"], t_next - t))
            continue
        if index[cell] < last:
            back.append(cell)
        last = max(last, index[cell])
        seen.add(cell)
    long_ones = [d for d in detours if d[2] > max_detour_s]
    want = set(route[index[runs[start][0]]:])
    coverage = len(seen & want) / float(len(want))
    if long_ones:
        raise CheckError("matched off the route for longer than %g s: %s" %
                         (max_detour_s, ", ".join("cell %d at %.1f s for %.1f s" % d for d in long_ones)))
    if len(back) > max_backwards:
        raise CheckError("%d steps back along the route (at most %d): to cells %s" % (len(back), max_backwards, back[:10]))
    if coverage < min_coverage:
        raise CheckError("matched %.0f %% of the route's cells from cell %d on (at least %.0f %%)" %
                         (100 * coverage, runs[start][0], 100 * min_coverage))
    if route[-1] not in seen:
        raise CheckError("the route's last cell %d was never matched (last: %s)" % (route[-1], [r[0] for r in runs[-3:]]))
    return {"runs": len(runs), "skipped": start, "detours": len(detours),
            "longest_detour_s": max([d[2] for d in detours] or [0]), "backwards": len(back), "coverage": coverage}


def _need(stats, key):
    node = stats
    for part in key.split("."):
        if not isinstance(node, dict) or part not in node:
            raise CheckError("the stats have no %s" % key)
        node = node[part]
    return node


def render_stats_sane(stats, png_files=None):
    """A rendering run's stats: frames rendered, none blank (nothing drawn, or
    black; a view filled by one flat-shaded wall is counted apart as
    uniform_frames, and may be at most one frame in ten), degraded frames
    counted (0..rendered), frame-time percentiles positive and ordered, and
    (png_files: the PNGs found) one PNG per rendered frame."""
    n = _need(stats, "rendered_frames")
    blank, degraded = _need(stats, "blank_frames"), _need(stats, "degraded_frames")
    p = [_need(stats, "frame_ms_p%d" % q) for q in (50, 95, 99)]
    if n <= 0:
        raise CheckError("no frame was rendered")
    if blank:
        raise CheckError("%d of %d frames are blank" % (blank, n))
    uniform = stats.get("uniform_frames", 0)
    if uniform * 10 > n:
        raise CheckError("%d of %d frames are one colour" % (uniform, n))
    if not 0 <= degraded <= n:
        raise CheckError("degraded_frames %s is not within 0..%d" % (degraded, n))
    if not 0 < p[0] <= p[1] <= p[2] < 60000:
        raise CheckError("frame-time percentiles p50 %s, p95 %s, p99 %s ms are not 0 < p50 <= p95 <= p99 < 60 s" %
                         tuple(p))
    if png_files is not None and not len(png_files) == _need(stats, "png_written") == n:
        raise CheckError("%d frames rendered, png_written %s, %d PNG files" % (n, stats["png_written"], len(png_files)))
    return {"rendered": n, "degraded": degraded, "frame_ms_p50": p[0], "frame_ms_p99": p[2]}


def memory_stats_sane(stats, runtime):
    """The stats' resident memory: the process RSS (peak >= now > 0) and, from
    a C API runtime (runtime=True), blvd_runtime_stats' residency and pools:
    1..max resident cells, pools used <= high water <= capacity, package tables
    and tracker memory held, no load errors."""
    m = _need(stats, "memory")
    rss, peak = _need(stats, "memory.rss_bytes"), _need(stats, "memory.rss_peak_bytes")
    if not 0 < rss <= peak:
        raise CheckError("resident memory %s bytes, peak %s: expected 0 < rss <= peak" % (rss, peak))
    if not runtime:
        return {"rss_bytes": rss}
    cells, most = _need(stats, "memory.resident_cells"), _need(stats, "memory.max_resident_cells")
    if not 1 <= cells <= most:
        raise CheckError("resident_cells %s not within 1..max_resident_cells %s" % (cells, most))
    for pool in ("gpu", "staging"):
        u, h, c = (_need(stats, "memory.%s.%s" % (pool, k)) for k in ("used_bytes", "high_water_bytes", "capacity_bytes"))
        if not 0 <= u <= h <= c or c <= 0:
            raise CheckError("%s pool: used %s, high water %s, capacity %s: expected used <= high water <= capacity, "
                             "capacity > 0" % (pool, u, h, c))
    for k in ("table_bytes", "tracking_bytes"):
        if _need(stats, "memory." + k) <= 0:
            raise CheckError("memory.%s is %s" % (k, m[k]))
    if _need(stats, "memory.load_errors"):
        raise CheckError("%s cells failed to load" % m["load_errors"])
    return {"rss_bytes": rss, "resident_cells": cells, "gpu_high_water_bytes": m["gpu"]["high_water_bytes"]}


def heading_follows_yaw_rate(poses, odometry, start_heading_deg, tol_deg):
    """Each valid pose's heading (clockwise from north) equals the start heading
    minus the integral of the decoded yaw rate (counter-clockwise positive,
    zero-order hold between samples) up to the pose's time, within tol_deg:
    the tracker turned as the bus said. Returns the worst difference and the
    total turn."""
    yaw = [(o["t"], o["yaw_rate"]) for o in odometry if o["flags"] & 4]
    valid = [p for p in poses if p["flags"] & 1]
    if not yaw or not valid:
        raise CheckError("%d yaw-rate samples, %d valid poses" % (len(yaw), len(valid)))
    k, turned, worst = 0, 0.0, 0.0
    for i, p in enumerate(valid):
        while k + 1 < len(yaw) and yaw[k + 1][0] <= p["t"]:
            turned += yaw[k][1] * (yaw[k + 1][0] - yaw[k][0])
            k += 1
        want = start_heading_deg - turned
        d = abs((p["heading"] - want + 180.0) % 360.0 - 180.0)
        if d > tol_deg:
            raise CheckError("pose %d (t %.3f): heading %.3f, the yaw rate integrates to %.3f (|diff| %.3f > %g deg)" %
                             (i, p["t"], p["heading"], want % 360.0, d, tol_deg))
        worst = max(worst, d)
    return {"poses": len(valid), "max_heading_diff_deg": worst, "turned_deg": -turned}
