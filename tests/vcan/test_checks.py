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


if __name__ == "__main__":
    unittest.main()
