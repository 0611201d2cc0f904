#!/usr/bin/env bash
# The samples build against the installed SDK, not only in-tree: install this
# build into a temporary prefix, configure every sample on its own with
# find_package(blvd) from that prefix, build it, and run each one briefly.
# Usage: test_installed_sdk.sh BUILD_DIR SOURCE_DIR PACKAGE WORKDIR
set -euo pipefail
build=$1 src=$2 pkg=$3 work=$4
rm -rf "$work"
mkdir -p "$work"

# step NAME CMD...: runs CMD with its output in $work/NAME.log; on failure shows the log's end.
step() {
  local name=$1
  shift
  if ! "$@" > "$work/$name.log" 2>&1; then
    echo "FAIL: $name: $*" >&2
    tail -n 40 "$work/$name.log" >&2
    exit 1
  fi
}

step install cmake --install "$build" --prefix "$work/prefix"
prefix=$work/prefix
for f in lib/cmake/blvd/blvdConfig.cmake lib/cmake/blvd/blvdAdaptersTargets.cmake include/blvd/blvd.h \
         include/blvd/adapters/gnss/nmea.h include/blvd/adapters/replay/replayer.h include/blvd/internal/track/tracker.h \
         lib/libblvd_adapter_gnss.a lib/libblvd_internals.a; do
  test -f "$prefix/$f" || { echo "FAIL: not installed: $f" >&2; exit 1; }
done

for s in host_context sim_feed gnss_replay vcan_drive; do
  step "$s-configure" cmake -S "$src/samples/$s" -B "$work/$s" -DCMAKE_PREFIX_PATH="$prefix"
  step "$s-build" cmake --build "$work/$s"
done

# The C API samples must use the installed library, not the build tree's.
for exe in host_context/host_context gnss_replay/gnss_replay vcan_drive/vcan_drive; do
  ldd "$work/$exe" > "$work/ldd.txt"
  grep -q "$prefix/lib/libblvd.so.0" "$work/ldd.txt" || { echo "FAIL: $exe does not load $prefix/lib/libblvd.so.0" >&2; cat "$work/ldd.txt" >&2; exit 1; }
done

# A short run of each: sim_feed drives 8 cells, gnss_replay and vcan_drive replay that drive.
step host_context-run "$work/host_context/host_context" "$pkg" -o "$work/frame.png"
step sim_feed-run "$work/sim_feed/sim_feed" --package "$pkg" --seed 3 --cells 8 --nmea "$work/drive.nmea" \
  --can "$work/drive.log" --truth "$work/drive.csv"
step gnss_replay-run "$work/gnss_replay/gnss_replay" "$work/drive.nmea" --package "$pkg" --fps 1 --width 160 \
  --height 96 --frames "$work/gr-frames" --stats "$work/gr-stats.json"
test -f "$work/gr-frames/frame_000000.png" || { echo "FAIL: gnss_replay wrote no frame" >&2; exit 1; }
step vcan_drive-run "$work/vcan_drive/vcan_drive" --candump "$work/drive.log" --nmea "$work/drive.nmea" \
  --package "$pkg" --width 160 --height 96 --render-every 20 --frames "$work/vd-frames" --stats "$work/vd-stats.json"
test -f "$work/vd-frames/frame_000000.png" || { echo "FAIL: vcan_drive wrote no frame" >&2; exit 1; }
step vcan_drive_track-run "$work/vcan_drive/vcan_drive_track" --candump "$work/drive.log" --nmea "$work/drive.nmea" \
  --package "$pkg" --stats "$work/vdt-stats.json"
grep -q '"valid_poses": [1-9]' "$work/vdt-stats.json" || { echo "FAIL: vcan_drive_track: no valid pose" >&2; exit 1; }
echo "installed SDK in $prefix: host_context, sim_feed, gnss_replay, vcan_drive, vcan_drive_track built and ran"
