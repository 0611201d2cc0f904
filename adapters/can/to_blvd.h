// A received frame as the C API's blvd_can_frame, for blvd_feed_can_frame() and
// blvd_can_profile_decode(). Shared by the samples and the trace tests: the
// adapter's only contact with libblvd is this public struct (as gnss/to_blvd.h).
#pragma once

#include <algorithm>

#include "blvd/blvd.h"
#include "can/frame.h"

namespace blvd::can {

inline blvd_can_frame toBlvd(const Frame& f) {
  blvd_can_frame out{};
  out.struct_size = sizeof out;
  out.t = f.t;
  out.id = f.id;
  out.flags = (f.extended ? BLVD_CAN_EXTENDED : 0u) | (f.rtr ? BLVD_CAN_RTR : 0u) | (f.error ? BLVD_CAN_ERROR : 0u) |
              (f.fd ? BLVD_CAN_FD : 0u);
  out.len = f.dlc;
  std::copy(f.data, f.data + std::min<size_t>(f.dlc, sizeof out.data), out.data);
  return out;
}

}  // namespace blvd::can
