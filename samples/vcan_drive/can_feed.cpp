#include "can_feed.h"

#include <algorithm>

#include "can/to_blvd.h"

namespace vcan_drive {

blvd_status CanFeed::open(const std::string& dbc_path, blvd_vehicle vehicle, std::string& err) {
  blvd_can_profile_desc pd{};
  pd.struct_size = sizeof pd;
  pd.vehicle = vehicle;
  pd.dbc_path = dbc_path.c_str();
  const blvd_status st = blvd_can_profile_create(&pd, &profile_);
  if (st != BLVD_OK) {
    err = blvd_last_error(nullptr);
    return st;
  }
  uint32_t n = 0;
  blvd_can_profile_message_ids(profile_, nullptr, 0, &n);
  std::vector<blvd_can_message_id> ids(n);
  blvd_can_profile_message_ids(profile_, ids.data(), n, &n);
  for (const blvd_can_message_id& m : ids) ids_.emplace_back(m.id, (m.flags & BLVD_CAN_EXTENDED) != 0);
  std::sort(ids_.begin(), ids_.end());  // (id, extended), for binary_search in feed()
  return BLVD_OK;
}

bool CanFeed::feed(const blvd::can::Frame& f, Tracking& tracking, blvd_odometry& odo) {
  ++stats_.frames;
  const blvd_can_frame frame = blvd::can::toBlvd(f);
  if (tracking.feedsCanFrames()) {
    // The whole bus goes to the C API; frames without the profile's signals are ignored there.
    if (tracking.feedCanFrame(frame) == BLVD_OK)
      ++stats_.can_frames_fed;
    else
      ++stats_.feed_errors;
  }
  if (std::binary_search(ids_.begin(), ids_.end(), std::make_pair(f.id, f.extended))) ++stats_.mapped;
  odo = blvd_odometry{};
  odo.struct_size = sizeof odo;
  // BLVD_ERR_NOT_FOUND: another message, or only the steering angle (the tracker has no use for it).
  if (blvd_can_profile_decode(profile_, &frame, &odo) != BLVD_OK) return false;
  if (!tracking.feedsCanFrames() && tracking.feedOdometry(odo) != BLVD_OK) {
    ++stats_.feed_errors;
    return false;
  }
  ++stats_.odometry_fed;
  return true;
}

}  // namespace vcan_drive
