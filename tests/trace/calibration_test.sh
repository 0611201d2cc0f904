#!/usr/bin/env bash
# trace.vcan_drive_calibration: samples/vcan_drive keeps the odometry calibration
# and the last pose between drives (--calibration FILE): the first drive of the
# sim_feed trace finds no file and writes what it learnt (the simulator's car: wheel
# scale 1.01, yaw-rate bias 0.2 deg/s) and where it ended; the second reads them
# back before its first fix; a drive out of a garage (CAN only, no GNSS at all)
# from a stored pose at the trace's start is matched to the true cells; a damaged
# or impossible file stops the program naming the file.
# Usage: calibration_test.sh VCAN_DRIVE_TRACK TRACE_PREFIX PACKAGE WORK
set -euo pipefail
drive=$1 trace=$2 package=$3 work=$4
fail() { echo "FAIL: $*" >&2; exit 1; }
rm -rf "$work" && mkdir -p "$work"
cal=$work/calibration.json
run() { "$drive" --candump "$trace.log" --nmea "$trace.nmea" --package "$package" --calibration "$cal" --stats "$work/stats$1.json" 2>"$work/err$1.txt"; }

run 1 || fail "first drive: $(cat "$work/err1.txt")"
[ -f "$cal" ] || fail "no calibration written"
python3 - "$cal" "$work/stats1.json" 0 "$trace.csv" <<'PY' || fail "first drive's calibration"
import csv, json, math, sys
cal, stats, loaded = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))["calibration"], int(sys.argv[3])
assert stats["loaded"] == bool(loaded), stats
# Where the drive ended (the last truth row, at most a second before the end).
last = list(csv.DictReader(open(sys.argv[4])))[-1]
sp = cal["start_pose"]
assert stats["start_pose_written"] is True and stats["start_pose_loaded"] is False, stats
d = math.hypot((sp["lat"] - float(last["lat"])) * 111132, (sp["lon"] - float(last["lon"])) * 80500)
assert d < 20, (sp, last, d)
assert 0.5 <= sp["sigma_m"] < 5 and 0 < sp["heading_sigma_deg"] < 10, sp
assert abs(cal["speed_scale"] - 1.01) < 0.003, cal          # the simulator's wheel-speed scale
assert abs(cal["yaw_rate_bias_dps"] - 0.2) < 0.1, cal       # and its gyro bias
assert 0 < cal["speed_scale_sigma"] < 0.005 and 0 < cal["yaw_rate_bias_sigma_dps"] < 0.5, cal
assert abs(cal["speed_scale"] - stats["speed_scale"]) < 1e-12, (cal, stats)
PY
cp "$cal" "$work/first.json"
run 2 || fail "second drive: $(cat "$work/err2.txt")"
python3 - "$cal" "$work/stats2.json" 1 "$work/first.json" <<'PY' || fail "second drive's calibration"
import json, sys
cal, stats, first = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))["calibration"], json.load(open(sys.argv[4]))
assert stats["loaded"] is True and stats["start_pose_loaded"] is True, stats
assert abs(cal["speed_scale"] - 1.01) < 0.003, cal
PY

# Key-on in an underground car park: no GNSS at all, only CAN, from a stored pose at
# the trace's start (the first truth row moved back along its heading by its arc:
# the car starts at the cell's origin) with the first drive's calibration.
python3 - "$work/first.json" "$trace.csv" "$work/garage.json" <<'PY' || fail "garage state file"
import csv, json, math, sys
state, row = json.load(open(sys.argv[1])), next(csv.DictReader(open(sys.argv[2])))
h, back = math.radians(float(row["heading_deg"])), float(row["arc_m"])
lat = float(row["lat"]) - back * math.cos(h) / 111132.0
lon = float(row["lon"]) - back * math.sin(h) / (111320.0 * math.cos(math.radians(lat)))
state["start_pose"] = {"lat": lat, "lon": lon, "heading_deg": float(row["heading_deg"]), "sigma_m": 1.0, "heading_sigma_deg": 2.0}
json.dump(state, open(sys.argv[3], "w"))
PY
"$drive" --candump "$trace.log" --package "$package" --calibration "$work/garage.json" --poses "$work/garage-poses.jsonl" \
  --stats "$work/stats-garage.json" 2>"$work/err-garage.txt" || fail "garage drive: $(cat "$work/err-garage.txt")"
python3 - "$work/garage-poses.jsonl" "$trace.csv" "$work/stats-garage.json" <<'PY' || fail "garage drive's cells"
import csv, json, sys
poses = [json.loads(l) for l in open(sys.argv[1])]
truth = list(csv.DictReader(open(sys.argv[2])))
stats = json.load(open(sys.argv[3]))
assert stats["calibration"]["start_pose_loaded"] is True and stats["gnss_fed"] == 0, stats["calibration"]
assert poses and all(p["flags"] & 1 for p in poses), "a pose without a position"  # valid from the first frame
t0 = float(truth[0]["t"]) - 1.0
# Every truth second of the first minute against the pose nearest to it in time.
rows = [r for r in truth if float(r["t"]) - t0 <= 60]
near = [min(poses, key=lambda p: abs(p["t"] - float(r["t"]))) for r in rows]
assert all(abs(p["t"] - float(r["t"])) <= 0.1 for p, r in zip(near, rows)), "no pose near a truth epoch"
on = sum(1 for p, r in zip(near, rows) if p["cell"] == int(r["cell"]))
assert on >= 0.9 * len(rows), "%d of %d truth epochs of the first minute on the true cell" % (on, len(rows))
print("garage: %d of %d epochs of the first minute on the true cell, no fix" % (on, len(rows)))
PY

# Damaged and impossible files: exit 2, the file named, nothing overwritten.
refused() {  # N CONTENT MESSAGE_PATTERN
  printf '%s' "$2" >"$cal"
  set +e
  run "$1"
  local rc=$?
  set -e
  [ $rc -eq 2 ] || fail "calibration '$2': exit $rc, want 2"
  grep -q "$3" "$work/err$1.txt" || fail "calibration '$2': message $(cat "$work/err$1.txt")"
  [ "$(cat "$cal")" = "$2" ] || fail "a refused calibration file was overwritten"
}
refused 3 '{"speed_scale": 1.01' "$cal: not JSON"
refused 4 '{"speed_scale": 3, "speed_scale_sigma": 0, "yaw_rate_bias_dps": 0, "yaw_rate_bias_sigma_dps": 0}' "$cal: .*speed_scale 3 .*must lie in"
refused 5 '{"speed_scale": 1.01}' "$cal: no number \"speed_scale_sigma\""
good='"speed_scale": 1.01, "speed_scale_sigma": 0, "yaw_rate_bias_dps": 0, "yaw_rate_bias_sigma_dps": 0'
refused 6 "{$good, \"start_pose\": {\"lat\": 43.7}}" "$cal: start_pose: no number \"lon\""
refused 7 "{$good, \"start_pose\": {\"lat\": 95, \"lon\": 7.4, \"heading_deg\": 0, \"sigma_m\": 1, \"heading_sigma_deg\": 1}}" "$cal: .*refused\|$cal: .*lat 95"
echo "trace.vcan_drive_calibration: ok"
