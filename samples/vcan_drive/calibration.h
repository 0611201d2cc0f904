// The odometry calibration kept between drives (--calibration FILE): what a
// head unit keeps in non-volatile memory at key-off and gives back to
// blvd_set_odometry_calibration at the next start. The file is a JSON object:
//   {"speed_scale": 1.0098, "speed_scale_sigma": 0.0007,
//    "yaw_rate_bias_dps": 0.2, "yaw_rate_bias_sigma_dps": 0.004}
#pragma once

#include <string>

#include "blvd/blvd.h"

namespace vcan_drive {

enum class CalibrationRead { Loaded, Missing, Bad };

// Missing: no such file (the first drive). Bad: `err` names the file and what is wrong.
CalibrationRead readCalibration(const std::string& path, blvd_odometry_calibration& out, std::string& err);

// Writes through a temporary file renamed over `path`, so a crash mid-write
// leaves the previous calibration. False with `err` on failure.
bool writeCalibration(const std::string& path, const blvd_odometry_calibration& cal, std::string& err);

}  // namespace vcan_drive
