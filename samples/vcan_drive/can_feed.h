// CAN frame -> tracker. Today the frame is decoded here, with adapters/can's
// DBC and vehicle profile, and fed as blvd_odometry. When the C API gains
// blvd_feed_can_frame() (issue 5), CanFeed::feed() becomes that one call and
// the DBC/profile move behind it; nothing else in vcan_drive changes.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "vehicle/dbc.h"
#include "can/frame.h"
#include "vehicle/profile.h"
#include "tracking.h"

namespace vcan_drive {

struct CanFeedStats {
  uint64_t frames = 0;          // frames seen
  uint64_t mapped = 0;          // frames that carried a profile signal
  uint64_t odometry_fed = 0;    // blvd_odometry samples fed
  uint64_t feed_errors = 0;     // feeds the tracker refused
};

class CanFeed {
 public:
  // Loads the DBC and binds the vehicle profile. `err` says what is missing.
  blvd_status open(const std::string& dbc_path, blvd::vehicle::Vehicle vehicle, std::string& err);

  // Feeds one frame. Returns true when it changed the odometry; `odo` is then
  // what was fed (also for the caller's odometry log).
  bool feed(const blvd::can::Frame& f, Tracking& tracking, blvd_odometry& odo);

  // (id, extended) of the messages the profile reads: the socket's filters.
  std::vector<std::pair<uint32_t, bool>> messageIds() const { return profile_.messageIds(); }
  const blvd::vehicle::Odometry& state() const { return profile_.state(); }
  const CanFeedStats& stats() const { return stats_; }

 private:
  blvd::vehicle::Database dbc_;
  blvd::vehicle::Profile profile_;
  CanFeedStats stats_;
};

}  // namespace vcan_drive
