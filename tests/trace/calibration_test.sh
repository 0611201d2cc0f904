#!/usr/bin/env bash
# trace.vcan_drive_calibration: samples/vcan_drive keeps the odometry calibration
# between drives (--calibration FILE): the first drive of the sim_feed trace finds
# no file and writes what it learnt (the simulator's car: wheel scale 1.01, yaw-rate
# bias 0.2 deg/s); the second reads it back before its first fix; a damaged or
# impossible file stops the program naming the file.
# Usage: calibration_test.sh VCAN_DRIVE_TRACK TRACE_PREFIX PACKAGE WORK
set -euo pipefail
drive=$1 trace=$2 package=$3 work=$4
fail() { echo "FAIL: $*" >&2; exit 1; }
rm -rf "$work" && mkdir -p "$work"
cal=$work/calibration.json
run() { "$drive" --candump "$trace.log" --nmea "$trace.nmea" --package "$package" --calibration "$cal" --stats "$work/stats$1.json" 2>"$work/err$1.txt"; }

run 1 || fail "first drive: $(cat "$work/err1.txt")"
[ -f "$cal" ] || fail "no calibration written"
python3 - "$cal" "$work/stats1.json" 0 <<'PY' || fail "first drive's calibration"
import json, sys
cal, stats, loaded = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))["calibration"], int(sys.argv[3])
assert stats["loaded"] == bool(loaded), stats
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
assert stats["loaded"] is True, stats
assert abs(cal["speed_scale"] - 1.01) < 0.003, cal
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
refused 4 '{"speed_scale": 3, "speed_scale_sigma": 0, "yaw_rate_bias_dps": 0, "yaw_rate_bias_sigma_dps": 0}' "$cal: .*refused"
refused 5 '{"speed_scale": 1.01}' "$cal: no number \"speed_scale_sigma\""
echo "trace.vcan_drive_calibration: ok"
