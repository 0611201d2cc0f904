#!/usr/bin/env python3
"""One tests/vcan run: a trace replayed onto vcan0 inside a Debian qemu guest
while vcan_drive_track tracks from the bus and candump captures it; then the
host checks what came back (see README.md for the interface).

Exit status: 0 pass, 1 a check failed, 77 skipped (no qemu, or Debian's
packages cannot be downloaded; with BLVD_VCAN_REQUIRE=1 that fails instead).
"""
import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import time

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import checks  # noqa: E402
import guest  # noqa: E402


def prepare_trace(src, log_iface, out):
    """The trace as plain text, only the frames of the logged interface that
    the canplayer mapping replays (those are what the bus will carry)."""
    if src.endswith(".zst"):
        data = subprocess.run(["zstd", "-dcq", src], check=True, stdout=subprocess.PIPE).stdout
    else:
        data = open(src, "rb").read()
    lines = [ln for ln in data.splitlines(keepends=True) if ln.split()[1:2] == [log_iface.encode()]]
    if not lines:
        raise checks.CheckError("%s has no frames on interface %s" % (src, log_iface))
    with open(out, "wb") as f:
        f.writelines(lines)


def run_in_guest(a, trace, out, summary):
    """The trace on vcan0 in the qemu guest; its /out lands in `out`."""
    guest.require_qemu()
    t = time.monotonic()
    g = guest.fetch(a.cache)
    summary["fetch_s"] = time.monotonic() - t
    files = {"/in/trace.log": trace, "/in/vehicle.dbc": a.dbc}
    drive_args = "--dbc /in/vehicle.dbc " + a.drive_args
    if a.package:
        files["/in/package.blvd"] = a.package
        drive_args += " --package /in/package.blvd"
    if a.nmea:
        # The bus is placed on the trace clock by the trace time of its first frame.
        files["/in/drive.nmea"] = a.nmea
        drive_args += " --nmea /in/drive.nmea --trace-t0 %.6f" % checks.read_candump(trace)[0][0]
    # The replay takes the trace's duration; the guest stops a scenario that
    # hangs early enough to send its logs back before the host's timeout.
    frames = checks.read_candump(trace)
    scenario_s = max(10, min(frames[-1][0] - frames[0][0] + 60, a.timeout_s - 40))
    env = {"TRACE": "/in/trace.log", "MAP": a.map, "DRIVE": "/bin/" + os.path.basename(a.drive),
           "DRIVE_ARGS": drive_args, "SCENARIO_TIMEOUT": int(scenario_s)}
    t = time.monotonic()
    initrd = guest.initramfs(g, os.path.join(a.work, "initrd.gz"), [a.drive], files,
                             os.path.join(guest.HERE, "scenario_replay.sh"), env)
    summary["initramfs_s"] = time.monotonic() - t
    summary["initramfs_bytes"] = os.path.getsize(initrd)
    vm = guest.boot(g, initrd, out, timeout_s=a.timeout_s, accel=a.accel)
    summary.update({"kernel": g["kver"], "accel": vm["accel"], "vm_s": vm["boot_s"]})


def run_on_host(a, trace, out, summary):
    """The same program reading the trace as a candump log (no bus): the
    scenario's outputs without the capture, for hosts without qemu."""
    os.makedirs(out)
    cmd = [a.drive, "--candump", trace, "--dbc", a.dbc, "--poses", os.path.join(out, "poses.jsonl"), "--odometry",
           os.path.join(out, "odometry.jsonl"), "--stats", os.path.join(out, "stats.json")]
    if a.package:
        cmd += ["--package", a.package]
    if a.nmea:
        cmd += ["--nmea", a.nmea]
    cmd += a.drive_args.split()
    t = time.monotonic()
    with open(os.path.join(out, "drive.err"), "w") as err:
        r = subprocess.run(cmd, stdout=err, stderr=subprocess.STDOUT, timeout=a.timeout_s)
    summary["drive_s"] = time.monotonic() - t
    with open(os.path.join(out, "scenario.rc"), "w") as f:
        f.write("%d\n" % r.returncode)


def show(path, what, tail=4000):
    if os.path.exists(path):
        text = open(path, errors="replace").read()[-tail:]
        sys.stderr.write("---- %s (%s) ----\n%s\n" % (what, path, text))


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--name", required=True, help="test name, for messages")
    ap.add_argument("--cache", required=True, help="guest package cache (shared between runs)")
    ap.add_argument("--work", required=True, help="this run's folder (emptied first)")
    ap.add_argument("--drive", required=True, help="vcan_drive_track binary")
    ap.add_argument("--trace", required=True, help="candump -l log (.zst allowed)")
    ap.add_argument("--map", default="vcan0=can0", help="canplayer assignment vcan0=LOGIFACE")
    ap.add_argument("--dbc", required=True)
    ap.add_argument("--package", help=".blvd package for map matching in the guest")
    ap.add_argument("--nmea", help="NMEA log on the trace's clock, fed by the drive in step with the bus")
    ap.add_argument("--drive-args", default="", help="more vcan_drive_track arguments")
    ap.add_argument("--reference-csv", help="assert the decoded 0xAA speed against this CSV")
    ap.add_argument("--speed-tol", type=float, default=1e-6)
    ap.add_argument("--time-tol", type=float, default=0.05, help="median replay timing offset, s")
    ap.add_argument("--time-max", type=float, default=2.0, help="worst replay timing offset, s")
    ap.add_argument("--distance-tol", type=float, default=0)
    ap.add_argument("--heading-tol", type=float, default=0,
                    help="assert the poses' heading against the integrated yaw rate from --start's heading, degrees")
    ap.add_argument("--expected-cells",
                    help="assert the matched cell sequence against this file (cells, or sim_feed's truth .csv)")
    ap.add_argument("--settle-s", type=float, default=10)
    ap.add_argument("--render-with", help="vcan_drive (full) to render the recorded poses on the host")
    ap.add_argument("--render-every", type=int, default=20)
    ap.add_argument("--max-wall-s", type=float, default=300)
    ap.add_argument("--timeout-s", type=float, default=240)
    ap.add_argument("--host", action="store_true",
                    help="no guest: run the drive on the trace as a candump log (no capture check)")
    ap.add_argument("--accel", default=os.environ.get("BLVD_VCAN_ACCEL", "tcg"), choices=["tcg", "kvm", "auto"])
    a = ap.parse_args()
    if a.distance_tol > 0 and not a.reference_csv:
        ap.error("--distance-tol needs --reference-csv")
    start = a.drive_args.split()
    start = start[start.index("--start") + 1:start.index("--start") + 4] if "--start" in start else []
    if a.heading_tol > 0 and len(start) != 3:
        ap.error("--heading-tol needs --start LAT LON HEADING in --drive-args")
    if a.render_with and not a.package:
        ap.error("--render-with needs --package")
    if "=" not in a.map:
        ap.error("--map must look like vcan0=can0")
    # A CTest timeout or ^C: unwind, so guest.boot() stops qemu.
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))

    t_start = time.monotonic()
    summary = {"test": a.name}
    shutil.rmtree(a.work, ignore_errors=True)
    os.makedirs(a.work)
    out = os.path.join(a.work, "out")
    try:
        log_iface = a.map.split("=", 1)[1]
        trace = os.path.join(a.work, "trace.log")
        prepare_trace(a.trace, log_iface, trace)

        if a.host:
            run_on_host(a, trace, out, summary)
        else:
            run_in_guest(a, trace, out, summary)
    except guest.Unavailable as e:
        return guest.unavailable_status(a.name, e)
    except (guest.GuestError, checks.CheckError, subprocess.SubprocessError, OSError) as e:
        print("%s: FAIL: %s" % (a.name, e))
        return 1

    try:
        rc = open(os.path.join(out, "scenario.rc")).read().strip()
        if rc != "0":
            for f, what in (("init.log", "guest init"), ("scenario.log", "scenario"), ("drive.err", "vcan_drive_track"),
                            ("candump.err", "candump")):
                show(os.path.join(out, f), what)
            show(os.path.join(out, "console.log"), "guest console", 3000)
            raise checks.CheckError("the guest scenario exited with %s%s" %
                                    (rc, " (killed by the guest's SCENARIO_TIMEOUT: it hung)" if rc == "137" else ""))
        sent = checks.read_candump(trace)
        bus = sent if a.host else checks.read_candump(os.path.join(out, "capture.log"))
        if not a.host:
            summary["frames"] = checks.same_frames(sent, bus)
        stats = json.load(open(os.path.join(out, "stats.json")))
        summary["drive"] = {k: stats[k] for k in ("frames", "odometry_fed", "gnss_fed", "kernel_dropped", "poses",
                                                   "valid_poses", "matched_poses", "error_frames", "wall_s")}
        if a.nmea and not stats["gnss_fed"]:
            raise checks.CheckError("no fix of %s was fed (gnss_untimed %d): are its times on the trace's clock?" %
                                    (a.nmea, stats["gnss_untimed"]))
        if stats["kernel_dropped"]:
            raise checks.CheckError("vcan_drive_track's socket dropped %d frames" % stats["kernel_dropped"])
        odo = checks.read_jsonl(os.path.join(out, "odometry.jsonl"))
        summary["stamps"] = checks.times_match_bus(odo, bus, 2e-6)
        if a.reference_csv:
            summary["speed"] = checks.speed_matches_reference(odo, a.reference_csv, 0xAA, a.speed_tol)
            summary["pacing"] = checks.paced_like_reference(odo, a.reference_csv, 0xAA, a.time_tol, a.time_max)
        poses = checks.read_jsonl(os.path.join(out, "poses.jsonl"))
        if a.distance_tol > 0:
            summary["distance"] = checks.distance_matches_reference(poses, a.reference_csv, a.distance_tol)
        if a.heading_tol > 0:
            summary["heading"] = checks.heading_follows_yaw_rate(poses, odo, float(start[2]), a.heading_tol)
        if a.expected_cells:
            # A sim_feed truth CSV, or a list of cells.
            expected = (checks.truth_cells(a.expected_cells) if a.expected_cells.endswith(".csv")
                        else checks.read_cells(a.expected_cells))
            summary["cells"] = checks.cells_match(poses, expected, a.settle_s)
        if a.render_with:
            frames = os.path.join(a.work, "frames")
            os.makedirs(frames)
            r = subprocess.run([a.render_with, "--render-poses", os.path.join(out, "poses.jsonl"), "--package",
                                a.package, "--frames", frames, "--render-every", str(a.render_every), "--stats",
                                os.path.join(a.work, "render.json")], stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
            if r.returncode != 0:
                raise checks.CheckError("rendering the recorded poses failed: " + r.stdout.decode(errors="replace")[-2000:])
            rs = json.load(open(os.path.join(a.work, "render.json")))
            if rs["rendered_frames"] == 0 or rs["blank_frames"] != 0:
                raise checks.CheckError("host rendering: %d frames, %d blank" % (rs["rendered_frames"], rs["blank_frames"]))
            summary["render"] = {k: rs[k] for k in ("rendered_frames", "blank_frames", "frame_ms_p50")}
        wall = time.monotonic() - t_start
        summary["wall_s"] = wall
        if wall > a.max_wall_s:
            raise checks.CheckError("the run took %.1f s, over the %.0f s limit" % (wall, a.max_wall_s))
    except (checks.CheckError, OSError, ValueError, KeyError) as e:
        print("%s: FAIL: %s\n%s" % (a.name, e, json.dumps(summary, indent=1)))
        return 1
    with open(os.path.join(a.work, "summary.json"), "w") as f:
        json.dump(summary, f, indent=1)
    print("%s: PASS %s" % (a.name, json.dumps(summary)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
