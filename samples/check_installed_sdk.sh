#!/usr/bin/env bash
# An installed SDK works for a host: the files are where blvdConfig.cmake and
# the .pc files say, the DBC files are installed, pkg-config compiles and links
# a C++ host, every sample configures with find_package(blvd) from the prefix,
# builds, loads the installed libblvd and runs briefly (frames rendered).
# Run by test_installed_sdk.sh on `cmake --install` into a folder, and by
# packaging/scripts/deb.sh in a clean root where the .deb files are installed.
# Usage: check_installed_sdk.sh PREFIX LIBDIR SOURCE_DIR PACKAGE WORKDIR
set -euo pipefail
prefix=$1 libdir=$2 src=$3 pkg=$4 work=$5
rm -rf "$work"
mkdir -p "$work"

# shellcheck source=samples/step.sh
source "$(dirname "$0")/step.sh"

for f in "$libdir"/cmake/blvd/blvdConfig.cmake "$libdir"/cmake/blvd/blvdAdaptersTargets.cmake \
         "$prefix"/include/blvd/blvd.h "$prefix"/include/blvd/adapters/gnss/nmea.h \
         "$prefix"/include/blvd/adapters/replay/replayer.h "$prefix"/include/blvd/internal/track/tracker.h \
         "$libdir"/libblvd_adapter_gnss.a "$libdir"/libblvd_internals.a; do
  test -f "$f" || { echo "FAIL: not installed: $f" >&2; exit 1; }
done
# The opendbc DBC files, byte for byte, with their licence note.
dbcdir=$prefix/share/blvd/dbc
for f in toyota_new_mc_pt_generated.dbc vw_mqb.dbc hyundai_2015_ccan.dbc LICENSE.md; do
  cmp -s "$src/tests/data/can/dbc/$f" "$dbcdir/$f" || { echo "FAIL: not installed (or differs): $dbcdir/$f" >&2; exit 1; }
done

# pkg-config from the prefix only: a C++ host of the adapters and internals (and
# libblvd, which blvd-adapters requires) compiles, links and runs with its flags.
export PKG_CONFIG_PATH=$libdir/pkgconfig
unset PKG_CONFIG_LIBDIR
for pc in blvd blvd-internals blvd-adapters; do
  step "pkgconfig-$pc" pkg-config --exists --print-errors "$pc"
done
pc_libdir=$(pkg-config --variable=libdir blvd-adapters)
[ "$(realpath "$pc_libdir")" = "$(realpath "$libdir")" ] ||
  { echo "FAIL: blvd-adapters.pc: libdir $pc_libdir is not $libdir" >&2; exit 1; }
[ "$(realpath "$(pkg-config --variable=dbcdir blvd-adapters)")" = "$(realpath "$dbcdir")" ] ||
  { echo "FAIL: blvd-adapters.pc: dbcdir is not $dbcdir" >&2; exit 1; }
pc_flags=$(pkg-config --cflags --libs blvd-adapters)
# Every -I and -L is the prefix's or the system's (the prefix lies in the build tree here, so name it first).
for f in $pc_flags; do
  case $f in
    -I* | -L*)
      case $(realpath -m "${f:2}") in
        "$(realpath "$prefix")"/* | /usr/*) ;;
        *) echo "FAIL: blvd-adapters.pc: $f is neither the prefix's nor the system's" >&2; exit 1 ;;
      esac ;;
  esac
done
cat > "$work/pc_host.cpp" <<'CPP'
#include <cstdio>
#include <string>

#include "blvd/blvd.h"
#include "can/candump.h"
#include "gnss/nmea.h"
#include "replay/replayer.h"
#include "sim/sim_feed.h"
#include "vehicle/dbc.h"

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  blvd::can::Record r;
  std::string reason;
  if (!blvd::can::parseLine("(1533198887.123456) can0 0AA#0102030405060708", r, reason)) return 3;
  blvd::vehicle::Database db;
  std::string err;
  if (db.load(argv[1], err) != blvd::core::Status::Ok || !db.find(0xAA, false)) {
    std::fprintf(stderr, "%s\n", err.c_str());
    return 4;
  }
  std::printf("blvd %s, %zu messages, %s\n", blvd_version_string(), db.messages().size(),
              blvd::gnss::nmeaErrorString(blvd::gnss::NmeaError::BadChecksum));
  return 0;
}
CPP
# shellcheck disable=SC2086  # pc_flags is a list of flags
step pkgconfig-build c++ -std=c++17 -o "$work/pc_host" "$work/pc_host.cpp" $pc_flags
step pkgconfig-run env LD_LIBRARY_PATH="$libdir" "$work/pc_host" "$dbcdir/toyota_new_mc_pt_generated.dbc"
grep -q "messages" "$work/pkgconfig-run.log" || { echo "FAIL: pc_host printed no summary" >&2; exit 1; }

for s in host_context sim_feed gnss_replay vcan_drive; do
  step "$s-configure" cmake -S "$src/samples/$s" -B "$work/$s" -DCMAKE_PREFIX_PATH="$prefix"
  step "$s-build" cmake --build "$work/$s"
done

# Built against the prefix, the samples' default DBC is the prefix's (CLI11 shows the default in
# --help; the runs below use it), and $BLVD_DATA_DIR comes first.
for exe in sim_feed/sim_feed vcan_drive/vcan_drive vcan_drive/vcan_drive_track; do
  step "$(basename "$exe")-help" "$work/$exe" --help
  grep -qF "$dbcdir/toyota_new_mc_pt_generated.dbc" "$work/$(basename "$exe")-help.log" ||
    { echo "FAIL: $exe: default --dbc is not $dbcdir/toyota_new_mc_pt_generated.dbc" >&2; grep -e --dbc "$work/$(basename "$exe")-help.log" >&2; exit 1; }
done
if BLVD_DATA_DIR="$work/no-data" "$work/sim_feed/sim_feed" --package "$pkg" --cells 2 --truth "$work/t.csv" \
     > "$work/sim_feed-env.log" 2>&1 || ! grep -qF "$work/no-data/dbc/toyota_new_mc_pt_generated.dbc" "$work/sim_feed-env.log"; then
  echo "FAIL: sim_feed ignored BLVD_DATA_DIR" >&2; cat "$work/sim_feed-env.log" >&2; exit 1
fi

# The C API samples must use the installed library, not the build tree's.
for exe in host_context/host_context gnss_replay/gnss_replay vcan_drive/vcan_drive; do
  ldd "$work/$exe" > "$work/ldd.txt"
  # (merged /usr: ldd may name /lib for /usr/lib)
  got=$(awk '/libblvd\.so\.0/ {print $3}' "$work/ldd.txt")
  [ -n "$got" ] && [ "$(realpath "$got")" = "$(realpath "$libdir/libblvd.so.0")" ] ||
    { echo "FAIL: $exe does not load $libdir/libblvd.so.0" >&2; cat "$work/ldd.txt" >&2; exit 1; }
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
echo "installed SDK in $prefix ($libdir): DBC files and pkg-config host checked; host_context, sim_feed, gnss_replay, vcan_drive, vcan_drive_track built and ran"
