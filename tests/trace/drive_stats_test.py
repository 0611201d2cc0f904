#!/usr/bin/env python3
"""trace.vcan_drive_stats: the sim_feed Monaco drive (fixture sim_feed_trace:
NMEA + candump + truth CSV) replayed through samples/vcan_drive's C API
pipeline from its candump and NMEA logs, with headless frames; the stats JSON
it writes must give frame-time percentiles, cells visited, resident memory and
degraded frames, and the cells visited must follow the truth's route
(tests/vcan/checks.py's cells_follow_route on the poses it also writes).

The assertions are tests/vcan/checks.py's (unit-tested by vcan.checks_unit)."""
import argparse
import glob
import json
import os
import shutil
import subprocess
import sys
import time

sys.dont_write_bytecode = True
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "vcan"))
import checks  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--drive", required=True, help="vcan_drive (the C API build)")
    ap.add_argument("--trace", required=True, help="sim_feed outputs without extension: .nmea, .log, .csv")
    ap.add_argument("--package", required=True)
    ap.add_argument("--work", required=True, help="this run's folder (emptied first)")
    ap.add_argument("--render-every", type=int, default=10)
    a = ap.parse_args()
    shutil.rmtree(a.work, ignore_errors=True)
    frames = os.path.join(a.work, "frames")
    os.makedirs(frames)
    stats_path = os.path.join(a.work, "stats.json")
    cmd = [a.drive, "--candump", a.trace + ".log", "--nmea", a.trace + ".nmea", "--package", a.package, "--frames",
           frames, "--render-every", str(a.render_every), "--poses", os.path.join(a.work, "poses.jsonl"), "--stats",
           stats_path]
    t = time.monotonic()
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    summary = {"drive_s": time.monotonic() - t}
    try:
        if r.returncode != 0:
            raise checks.CheckError("vcan_drive exited with %d:\n%s" % (r.returncode, r.stdout.decode(errors="replace")[-3000:]))
        stats = json.load(open(stats_path))
        if stats.get("can_feed") != "blvd_feed_can_frame" or not stats.get("can_frames_fed"):
            raise checks.CheckError("the C API runtime was not fed CAN frames (can_feed %r, can_frames_fed %r)" %
                                    (stats.get("can_feed"), stats.get("can_frames_fed")))
        if stats["feed_errors"] or not stats["gnss_fed"] or not stats["odometry_fed"]:
            raise checks.CheckError("feed_errors %d, gnss_fed %d, odometry_fed %d" %
                                    (stats["feed_errors"], stats["gnss_fed"], stats["odometry_fed"]))
        summary["render"] = checks.render_stats_sane(stats, glob.glob(os.path.join(frames, "frame_*.png")))
        summary["memory"] = checks.memory_stats_sane(stats, runtime=True)
        # cells_visited is the poses' matched sequence; with the poses' times it must
        # follow the truth's route (junction detours up to 3 s: 2.1 s measured at most).
        poses = checks.read_jsonl(os.path.join(a.work, "poses.jsonl"))
        summary["visited"] = checks.visited_equals_poses(stats["cells_visited"], poses)
        summary["cells"] = checks.cells_follow_route(poses, checks.truth_cells(a.trace + ".csv"), settle_s=10,
                                                     max_detour_s=3, max_backwards=2, min_coverage=0.9)
    except (checks.CheckError, OSError, ValueError, KeyError) as e:
        print("trace.vcan_drive_stats: FAIL: %s\n%s" % (e, json.dumps(summary, indent=1)))
        return 1
    print("trace.vcan_drive_stats: PASS %s" % json.dumps(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
