#include "can_feed.h"

#include "can/to_blvd.h"

namespace vcan_drive {

using namespace blvd::can;
using namespace blvd::vehicle;

static_assert(BLVD_ODO_SPEED == kOdoSpeed && BLVD_ODO_YAW_RATE == kOdoYawRate &&
                  BLVD_ODO_WHEEL_SPEEDS == kOdoWheelSpeeds && BLVD_ODO_GEAR == kOdoGear,
              "the profile's OdometryField bits are passed through as BLVD_ODO_* flags");

blvd_status CanFeed::open(const std::string& dbc_path, Vehicle vehicle, std::string& err) {
  // sdk/vehicle's statuses are the C API's values (core/status.h).
  if (const auto st = dbc_.load(dbc_path, err); st != blvd::core::Status::Ok) return static_cast<blvd_status>(st);
  ProfileDesc pd;
  pd.vehicle = vehicle;
  return static_cast<blvd_status>(profile_.create(pd, dbc_, err));
}

bool CanFeed::feed(const Frame& f, Tracking& tracking, blvd_odometry& odo) {
  ++stats_.frames;
  if (tracking.feedsCanFrames()) {
    // The whole bus goes to the C API; frames without the profile's signals are ignored there.
    if (tracking.feedCanFrame(toBlvd(f)) == BLVD_OK)
      ++stats_.can_frames_fed;
    else
      ++stats_.feed_errors;
  }
  Odometry o;
  if (!profile_.consume(f, o)) return false;
  ++stats_.mapped;
  const uint32_t flags = o.updated & (BLVD_ODO_SPEED | BLVD_ODO_YAW_RATE | BLVD_ODO_WHEEL_SPEEDS | BLVD_ODO_GEAR);
  if (!flags) return false;  // steering only: the tracker has no use for it
  odo = blvd_odometry{};
  odo.struct_size = sizeof odo;
  odo.t = o.t;
  odo.speed_mps = o.speed_mps;
  odo.yaw_rate_dps = o.yaw_rate_dps;
  for (int i = 0; i < 4; ++i) odo.wheel_speeds_mps[i] = o.wheel_speeds_mps[i];
  odo.reverse = o.gear == Gear::Reverse;
  odo.flags = flags;
  if (!tracking.feedsCanFrames() && tracking.feedOdometry(odo) != BLVD_OK) {
    ++stats_.feed_errors;
    return false;
  }
  ++stats_.odometry_fed;
  return true;
}

}  // namespace vcan_drive
