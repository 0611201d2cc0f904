// The C API's tracking inputs as sdk/track's structs. Used by the runtime's
// feeds and by `blvd bench track`, which tracks what the adapters produce for a
// host (blvd_gnss_fix / blvd_odometry) without a runtime. The flag bits are the
// same values (runtime.cpp checks them at compile time).
#pragma once

#include "blvd/blvd.h"
#include "capi/sized.h"
#include "track/types.h"

namespace blvd::capi {

inline track::GnssFix toTrack(const blvd_gnss_fix& in) {
  const blvd_gnss_fix f = sized(in);
  track::GnssFix g;
  g.t = f.t;
  g.lat = f.lat;
  g.lon = f.lon;
  g.alt = f.alt;
  g.speed_mps = f.speed_mps;
  g.track_deg = f.track_deg;
  g.hdop = f.hdop;
  g.h_acc_m = f.h_acc_m;
  g.mode = f.mode;
  g.flags = f.flags;  // BLVD_GNSS_HAS_* == track::GnssFlag bits
  return g;
}

inline track::Odometry toTrack(const blvd_odometry& in) {
  const blvd_odometry o = sized(in);
  track::Odometry d;
  d.t = o.t;
  d.speed_mps = o.speed_mps;
  d.yaw_rate_dps = o.yaw_rate_dps;
  for (int i = 0; i < 4; ++i) d.wheel_speeds_mps[i] = o.wheel_speeds_mps[i];
  d.heading_deg = o.heading_deg;
  d.reverse = o.reverse != 0;
  d.flags = o.flags;  // BLVD_ODO_* == track::OdometryFlag bits
  return d;
}

}  // namespace blvd::capi
