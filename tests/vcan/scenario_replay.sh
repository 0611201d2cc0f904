#!/bin/sh
# The tests/vcan scenario, inside the guest (guest_init.sh runs it with the
# variables of /scenario.env):
#   TRACE      candump -l log to replay (/in/...)
#   MAP        canplayer interface assignment, e.g. vcan0=can0
#   DRIVE      the tracking program (vcan_drive_track)
#   DRIVE_ARGS its arguments besides the interface and outputs
# candump captures vcan0 into /out/capture.log, vcan_drive_track tracks from
# vcan0 into /out/poses.jsonl, odometry.jsonl and stats.json, and canplayer
# replays the trace in real time. Both readers are open before the replay starts.
set -u
uptime_s() { cut -d' ' -f1 /proc/uptime; }

candump -L -r 4194304 vcan0 > /out/capture.log 2> /out/candump.err &
candump_pid=$!
# shellcheck disable=SC2086
"$DRIVE" --iface vcan0 --ready-file /tmp/drive.ready --poses /out/poses.jsonl --odometry /out/odometry.jsonl \
  --stats /out/stats.json $DRIVE_ARGS 2> /out/drive.err &
drive_pid=$!

i=0
while [ ! -e /tmp/drive.ready ]; do
  i=$((i + 1))
  if [ $i -gt 300 ] || ! kill -0 $drive_pid 2>/dev/null; then
    echo "scenario: $DRIVE did not open vcan0"; cat /out/drive.err; exit 3
  fi
  usleep 100000
done
# candump was started first and binds in milliseconds; the kernel's receive
# lists (one entry per reader and filter) go to the log.
usleep 200000
cat /proc/net/can/rcvlist_all /proc/net/can/rcvlist_fil 2>/dev/null

t0=$(uptime_s)
canplayer -I "$TRACE" "$MAP"
rc=$?
t1=$(uptime_s)
echo "scenario: canplayer exited with $rc after $t0 -> $t1 s of uptime"
echo "{\"replay_start_uptime_s\":$t0,\"replay_end_uptime_s\":$t1,\"canplayer_rc\":$rc}" > /out/replay.json
usleep 500000  # let the readers drain their queues
kill -INT $drive_pid $candump_pid
wait $drive_pid
drive_rc=$?
wait $candump_pid
echo "scenario: $DRIVE exited with $drive_rc"
[ $rc -eq 0 ] && [ $drive_rc -eq 0 ]
