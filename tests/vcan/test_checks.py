#!/usr/bin/env python3
"""Unit tests of checks.py on hand-made inputs: each assertion the vcan tests
rely on must pass on agreeing data and fail, naming the place, on data that
disagrees. Runs without qemu (CTest vcan.checks_unit)."""
import os
import sys
import tempfile
import unittest

sys.dont_write_bytecode = True
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import checks  # noqa: E402


def pose(t, cell, flags=0x5):
    return {"t": t, "x": 0.0, "y": 0.0, "heading": 0.0, "speed": 0.0, "cell": cell, "flags": flags}


class Frames(unittest.TestCase):
    sent = [(1.0, "can0", "0AA#01"), (1.1, "can0", "0B4#02"), (1.2, "can0", "0AA#03")]

    def test_equal(self):
        got = [(t + 100, "vcan0", f) for t, _, f in self.sent]
        self.assertEqual(checks.same_frames(self.sent, got), {"frames": 3})

    def test_payload_differs(self):
        got = [(0, "vcan0", "0AA#01"), (0, "vcan0", "0B4#FF"), (0, "vcan0", "0AA#03")]
        with self.assertRaisesRegex(checks.CheckError, "frame 1 differs"):
            checks.same_frames(self.sent, got)

    def test_missing_frame(self):
        with self.assertRaisesRegex(checks.CheckError, "replayed 3 frames, candump captured 2"):
            checks.same_frames(self.sent, [(0, "vcan0", f) for _, _, f in self.sent[:2]])


class Stamps(unittest.TestCase):
    bus = [(10.000001, "vcan0", "0AA#00"), (10.010000, "vcan0", "024#00"), (10.020000, "vcan0", "0AA#00")]

    def test_subsequence_per_id(self):
        odo = [{"t": 10.000001, "id": 0xAA}, {"t": 10.020001, "id": 0xAA}]
        self.assertEqual(checks.times_match_bus(odo, self.bus, 2e-6)["samples"], 2)

    def test_wrong_time(self):
        odo = [{"t": 10.000001, "id": 0xAA}, {"t": 10.010000, "id": 0xAA}]  # 0x24's time, not 0xAA's
        with self.assertRaisesRegex(checks.CheckError, "sample 1 \\(frame 0xAA\\)"):
            checks.times_match_bus(odo, self.bus, 2e-6)

    def test_no_samples(self):
        with self.assertRaises(checks.CheckError):
            checks.times_match_bus([], self.bus, 2e-6)


class Pacing(unittest.TestCase):
    def setUp(self):
        fd, self.csv = tempfile.mkstemp(suffix=".csv")
        with os.fdopen(fd, "w") as f:
            f.write("t_boot_s,speed_mps\n")
            for i in range(200):
                f.write("%.6f,%.6f\n" % (100 + 0.1 * i, 5 + 0.01 * i))

    def tearDown(self):
        os.remove(self.csv)

    def odo(self, rate=1.0, stall_at=None):
        out = []
        for i in range(200):
            t = 5000 + 0.1 * i * rate + (0.02 if i == 0 else 0)  # the first one late, as in the guest
            if stall_at is not None and i == stall_at:
                t += 3.0
            out.append({"t": t, "id": 0xAA, "speed": 5 + 0.01 * i})
        return out

    def test_real_time(self):
        self.assertLess(checks.paced_like_reference(self.odo(), self.csv, 0xAA, 0.05, 2.0)["median_s"], 1e-9)

    def test_one_percent_slow(self):
        with self.assertRaisesRegex(checks.CheckError, "median deviation"):
            checks.paced_like_reference(self.odo(rate=1.01), self.csv, 0xAA, 0.05, 2.0)

    def test_long_stall(self):
        with self.assertRaisesRegex(checks.CheckError, "worst 3.0"):
            checks.paced_like_reference(self.odo(stall_at=50), self.csv, 0xAA, 0.05, 2.0)

    def test_speed(self):
        odo = self.odo()
        self.assertEqual(checks.speed_matches_reference(odo, self.csv, 0xAA, 1e-6)["samples"], 200)
        odo[7]["speed"] += 1e-5
        with self.assertRaisesRegex(checks.CheckError, "sample 7 "):
            checks.speed_matches_reference(odo, self.csv, 0xAA, 1e-6)
        with self.assertRaisesRegex(checks.CheckError, "199 decoded samples"):
            checks.speed_matches_reference(odo[1:], self.csv, 0xAA, 1e-6)


class Cells(unittest.TestCase):
    expected = [10, 11, 12, 13, 14]

    def test_after_settling(self):
        # Unmatched and wrong cells in the first 10 s do not count; repeats collapse.
        poses = [pose(0, 99), pose(5, -1, 1), pose(11, 11), pose(12, 11), pose(13, 12), pose(14, 13), pose(15, 14)]
        self.assertEqual(checks.cells_match(poses, self.expected, 10), {"cells": 4})

    def test_wrong_cell(self):
        poses = [pose(0, 10), pose(11, 11), pose(12, 15), pose(13, 13), pose(14, 14)]
        with self.assertRaisesRegex(checks.CheckError, "matched 15, expected 12"):
            checks.cells_match(poses, self.expected, 10)

    def test_stops_short(self):
        poses = [pose(0, 10), pose(11, 11), pose(12, 12)]
        with self.assertRaisesRegex(checks.CheckError, "matched 2 cells after 10 s, expected 4"):
            checks.cells_match(poses, self.expected, 10)

    def test_unmatched_flags_ignored(self):
        poses = [pose(0, 10), pose(11, 11), pose(12, 99, flags=1), pose(13, 12), pose(14, 13), pose(15, 14)]
        self.assertEqual(checks.cells_match(poses, self.expected, 10), {"cells": 4})

    def test_read_cells(self):
        fd, path = tempfile.mkstemp()
        with os.fdopen(fd, "w") as f:
            f.write("# ground truth\n10\n11  # a comment\n\n12\n")
        try:
            self.assertEqual(checks.read_cells(path), [10, 11, 12])
        finally:
            os.remove(path)


def route_poses(cells, step=1.0):
    """A matched pose per second per listed cell; (cell, seconds) pairs stay longer."""
    out, t = [], 0.0
    for c in cells:
        c, n = c if isinstance(c, tuple) else (c, 1)
        for _ in range(n):
            out.append(pose(t, c))
            t += step
    return out


class Route(unittest.TestCase):
    route = list(range(100, 120))

    def follow(self, cells, **kw):
        args = dict(settle_s=2, max_detour_s=3, max_backwards=2, min_coverage=0.9)
        args.update(kw)
        return checks.cells_follow_route(route_poses(cells), self.route, **args)

    def test_follows(self):
        # Converging first (before 2 s), a short junction detour, one cell skipped between poses.
        r = self.follow([7, 8, 100, 101, 102, (555, 2), 103] + list(range(105, 120)))
        self.assertEqual((r["skipped"], r["detours"], r["longest_detour_s"], r["backwards"]), (0, 1, 2.0, 0))

    def test_long_detour(self):
        with self.assertRaisesRegex(checks.CheckError, "cell 555 at 4.0 s for 4.0 s"):
            self.follow([100, 101, 102, 103, (555, 4)] + list(range(104, 120)))

    def test_backwards(self):
        with self.assertRaisesRegex(checks.CheckError, "3 steps back"):
            self.follow(list(range(100, 110)) + [105, 110, 106, 111, 107] + list(range(112, 120)))

    def test_gaps(self):
        with self.assertRaisesRegex(checks.CheckError, "matched 56 % of the route.s cells from cell 104"):
            self.follow(self.route[::2] + [119])

    def test_stops_early(self):
        with self.assertRaisesRegex(checks.CheckError, "last cell 119 was never matched"):
            self.follow(self.route[:19])

    def test_nowhere_near(self):
        with self.assertRaisesRegex(checks.CheckError, "none of the 3 cells matched"):
            self.follow([1, 2, 3], settle_s=0)

    def test_visited_equals_poses(self):
        poses = route_poses([100, (101, 3), 102])
        poses.insert(2, pose(1.5, 999, flags=1))  # not matched: not a visit
        self.assertEqual(checks.visited_equals_poses([100, 101, 102], poses), {"cells": 3})
        with self.assertRaisesRegex(checks.CheckError, "at entry 1"):
            checks.visited_equals_poses([100, 102], poses)

    def test_truth_cells(self):
        fd, path = tempfile.mkstemp(suffix=".csv")
        with os.fdopen(fd, "w") as f:
            f.write("t,e,n,lat,lon,heading_deg,speed_mps,cell,arc_m,fix\n")
            for t, c in ((0, 5), (1, 5), (2, 9), (3, 4), (4, 4)):
                f.write("%d,0,0,0,0,0,0,%d,0,1\n" % (t, c))
        try:
            self.assertEqual(checks.truth_cells(path), [5, 9, 4])
        finally:
            os.remove(path)


def drive_stats():
    return {"rendered_frames": 4, "blank_frames": 0, "degraded_frames": 1, "png_written": 4,
            "frame_ms_p50": 10.0, "frame_ms_p95": 20.0, "frame_ms_p99": 30.0,
            "memory": {"rss_bytes": 100, "rss_peak_bytes": 200, "resident_cells": 3, "max_resident_cells": 8,
                       "gpu": {"used_bytes": 10, "high_water_bytes": 20, "capacity_bytes": 30},
                       "staging": {"used_bytes": 0, "high_water_bytes": 5, "capacity_bytes": 5},
                       "table_bytes": 7, "tracking_bytes": 9, "load_errors": 0}}


class DriveStats(unittest.TestCase):
    pngs = ["a.png", "b.png", "c.png", "d.png"]

    def bad(self, change, pattern, check="render"):
        s = drive_stats()
        change(s)
        with self.assertRaisesRegex(checks.CheckError, pattern):
            if check == "render":
                checks.render_stats_sane(s, self.pngs)
            else:
                checks.memory_stats_sane(s, True)

    def test_sane(self):
        self.assertEqual(checks.render_stats_sane(drive_stats(), self.pngs)["degraded"], 1)
        many = drive_stats()
        many.update(rendered_frames=20, png_written=20, uniform_frames=2)  # a wall at 2 corners of 20
        self.assertEqual(checks.render_stats_sane(many, ["p%d.png" % i for i in range(20)])["rendered"], 20)
        self.assertEqual(checks.memory_stats_sane(drive_stats(), True)["resident_cells"], 3)
        s = drive_stats()
        s["memory"] = {"rss_bytes": 1, "rss_peak_bytes": 1}  # track-only: no runtime figures
        self.assertEqual(checks.memory_stats_sane(s, False), {"rss_bytes": 1})

    def test_render(self):
        self.bad(lambda s: s.update(rendered_frames=0), "no frame was rendered")
        self.bad(lambda s: s.update(blank_frames=1), "1 of 4 frames are blank")
        self.bad(lambda s: s.update(uniform_frames=1), "1 of 4 frames are one colour")  # more than 1 in 10
        self.bad(lambda s: s.update(degraded_frames=5), "degraded_frames 5")
        self.bad(lambda s: s.pop("degraded_frames"), "no degraded_frames")
        self.bad(lambda s: s.update(frame_ms_p95=40.0), "percentiles")
        self.bad(lambda s: s.update(frame_ms_p50=0.0), "percentiles")
        self.bad(lambda s: s.update(png_written=3), "png_written 3")
        with self.assertRaisesRegex(checks.CheckError, "3 PNG files"):
            checks.render_stats_sane(drive_stats(), self.pngs[:3])

    def test_memory(self):
        self.bad(lambda s: s["memory"].update(rss_bytes=0), "resident memory 0", "memory")
        self.bad(lambda s: s["memory"].update(rss_peak_bytes=50), "expected 0 < rss <= peak", "memory")
        self.bad(lambda s: s["memory"].pop("rss_bytes"), "no memory.rss_bytes", "memory")
        self.bad(lambda s: s["memory"].update(resident_cells=0), "resident_cells 0", "memory")
        self.bad(lambda s: s["memory"]["gpu"].update(used_bytes=25), "gpu pool", "memory")
        self.bad(lambda s: s["memory"]["staging"].update(capacity_bytes=0), "staging pool", "memory")
        self.bad(lambda s: s["memory"].update(tracking_bytes=0), "memory.tracking_bytes is 0", "memory")
        self.bad(lambda s: s["memory"].update(load_errors=2), "2 cells failed", "memory")
        self.bad(lambda s: s.pop("memory"), "no memory", "memory")


class Heading(unittest.TestCase):
    # 2 deg/s counter-clockwise for 10 s, sampled at 10 Hz: the heading goes from 10 down to -10 (350).
    odo = sorted([{"t": 0.1 * i, "yaw_rate": 2.0, "flags": 4} for i in range(101)] + [{"t": 5.0, "flags": 16}],
                 key=lambda o: o["t"])  # a wheel-speed sample between: not a yaw rate

    def poses(self, err=0.0, at=None):
        return [dict(pose(0.1 * i, -1, 1), heading=(10.0 - 0.2 * i + (err if i == at else 0)) % 360) for i in range(101)]

    def test_follows(self):
        r = checks.heading_follows_yaw_rate(self.poses(), self.odo, 10.0, 0.01)
        self.assertLess(r["max_heading_diff_deg"], 1e-6)
        self.assertAlmostEqual(r["turned_deg"], -20.0)

    def test_off(self):
        with self.assertRaisesRegex(checks.CheckError, "pose 60 \\(t 6.000\\)"):
            checks.heading_follows_yaw_rate(self.poses(err=0.5, at=60), self.odo, 10.0, 0.25)

    def test_wrong_sign(self):
        flipped = [dict(o, yaw_rate=-o["yaw_rate"]) if "yaw_rate" in o else o for o in self.odo]
        with self.assertRaisesRegex(checks.CheckError, "pose 1 "):
            checks.heading_follows_yaw_rate(self.poses(), flipped, 10.0, 0.25)

    def test_no_yaw(self):
        with self.assertRaisesRegex(checks.CheckError, "0 yaw-rate samples"):
            checks.heading_follows_yaw_rate(self.poses(), [], 10.0, 0.25)


if __name__ == "__main__":
    unittest.main()
