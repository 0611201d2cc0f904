// What vcan_drive keeps between drives (--calibration FILE): the odometry
// calibration and the last pose, what a head unit keeps in non-volatile memory
// at key-off and gives back to blvd_set_odometry_calibration and
// blvd_set_start_pose at the next start. The file is a JSON object:
//   {"speed_scale": 1.0098, "speed_scale_sigma": 0.0007,
//    "yaw_rate_bias_dps": 0.2, "yaw_rate_bias_sigma_dps": 0.004,
//    "start_pose": {"lat": 43.73, "lon": 7.42, "heading_deg": 211.0,
//                   "sigma_m": 0.6, "heading_sigma_deg": 1.2}}
// "start_pose" is optional (a drive that ended without a pose writes none).
#pragma once

#include <string>

#include "blvd/blvd.h"

namespace vcan_drive {

struct KeyOffState {
  blvd_odometry_calibration calibration{};
  bool has_pose = false;
  blvd_start_pose pose{};  // t is the next start's, set by the caller
};

enum class CalibrationRead { Loaded, Missing, Bad };

// Missing: no such file (the first drive). Bad: `err` names the file and what is wrong.
CalibrationRead readCalibration(const std::string& path, KeyOffState& out, std::string& err);

// Writes through a temporary file renamed over `path`, so a crash mid-write
// leaves the previous state. False with `err` on failure.
bool writeCalibration(const std::string& path, const KeyOffState& state, std::string& err);

}  // namespace vcan_drive
