// A decoded fix as the C API's blvd_gnss_fix, for blvd_feed_gnss(). Shared by
// the replayer and the samples: the adapter's only contact with libblvd is
// this public struct.
#pragma once

#include "blvd/blvd.h"
#include "gnss/fix.h"

namespace blvd::gnss {

inline blvd_gnss_fix toBlvd(const Fix& f) {
  blvd_gnss_fix out{};
  out.struct_size = sizeof out;
  out.t = f.t_unix;
  out.lat = f.lat;
  out.lon = f.lon;
  out.alt = f.alt;
  out.speed_mps = f.speed_mps;
  out.track_deg = f.track_deg;
  out.hdop = f.hdop;
  out.h_acc_m = f.h_acc_m;
  out.mode = static_cast<blvd_gnss_mode>(f.mode);
  // The first seven FixFlag bits are the BLVD_GNSS_HAS_* bits (fix.h keeps them in step).
  out.flags = f.flags & (BLVD_GNSS_HAS_TIME | BLVD_GNSS_HAS_LATLON | BLVD_GNSS_HAS_ALT | BLVD_GNSS_HAS_SPEED |
                         BLVD_GNSS_HAS_TRACK | BLVD_GNSS_HAS_HDOP | BLVD_GNSS_HAS_HACC);
  return out;
}

}  // namespace blvd::gnss
