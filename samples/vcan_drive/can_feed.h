// CAN frame -> tracker. The frame is decoded here with a blvd_can_profile of
// its own (blvd_can_profile_decode) for the odometry log, the stats and the
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

#include "blvd/blvd.h"
#include "can/frame.h"
#include "tracking.h"

namespace vcan_drive {

struct CanFeedStats {
  uint64_t frames = 0;          // frames seen
  uint64_t mapped = 0;          // frames of a message the profile reads
  uint64_t odometry_fed = 0;    // decoded blvd_odometry samples (the ones the tracker received)
  uint64_t feed_errors = 0;     // feeds the tracker refused
  uint64_t can_frames_fed = 0;  // frames passed whole to blvd_feed_can_frame (C API tracker)
};

class CanFeed {
 public:
  CanFeed() = default;
  CanFeed(const CanFeed&) = delete;
  CanFeed& operator=(const CanFeed&) = delete;
  ~CanFeed() { blvd_can_profile_destroy(profile_); }

  // Loads the DBC and binds the vehicle profile. `err` says what is missing.
  blvd_status open(const std::string& dbc_path, blvd_vehicle vehicle, std::string& err);

  // Feeds one frame. Returns true when it changed the odometry; `odo` is then
  // the decoded sample (for the caller's odometry log).
  bool feed(const blvd::can::Frame& f, Tracking& tracking, blvd_odometry& odo);

  // (id, extended) of the messages the profile reads: the socket's filters.
  const std::vector<std::pair<uint32_t, bool>>& messageIds() const { return ids_; }
  const CanFeedStats& stats() const { return stats_; }

 private:
  blvd_can_profile* profile_ = nullptr;
  std::vector<std::pair<uint32_t, bool>> ids_;  // what the profile reads, sorted
  CanFeedStats stats_;
};

}  // namespace vcan_drive
