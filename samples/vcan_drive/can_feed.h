// CAN frame -> tracker. The frame is decoded here with the SDK's DBC and
// vehicle profile (sdk/vehicle) for the odometry log, the stats and the
// socket's filters. The tracker is fed either the whole frame, which the C
// API decodes itself with its own profile (blvd_feed_can_frame: vcan_drive's
// C API runtime), or the decoded blvd_odometry (blvd_feed_odometry's
// equivalent: the blvd_tracker of vcan_drive_track and --no-render). Both
// profiles see the same frames, so the log holds what the tracker was fed.
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
  uint64_t odometry_fed = 0;    // decoded blvd_odometry samples (the ones the tracker received)
  uint64_t feed_errors = 0;     // feeds the tracker refused
  uint64_t can_frames_fed = 0;  // frames passed whole to blvd_feed_can_frame (C API tracker)
};

class CanFeed {
 public:
  // Loads the DBC and binds the vehicle profile. `err` says what is missing.
  blvd_status open(const std::string& dbc_path, blvd::vehicle::Vehicle vehicle, std::string& err);

  // Feeds one frame. Returns true when it changed the odometry; `odo` is then
  // the decoded sample (for the caller's odometry log).
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
