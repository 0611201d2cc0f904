#include "calibration.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>

#include <nlohmann/json.hpp>

namespace vcan_drive {

CalibrationRead readCalibration(const std::string& path, blvd_odometry_calibration& out, std::string& err) {
  // fopen, not ifstream: its errno tells a missing file (the first drive) from an unreadable one.
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) {
    if (errno == ENOENT) return CalibrationRead::Missing;
    err = path + ": " + std::strerror(errno);
    return CalibrationRead::Bad;
  }
  std::string text;
  char buf[4096];
  for (size_t n; (n = std::fread(buf, 1, sizeof buf, f)) > 0;) text.append(buf, n);
  const bool read_error = std::ferror(f) != 0;
  std::fclose(f);
  if (read_error) {
    err = path + ": read error";
    return CalibrationRead::Bad;
  }
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    err = path + ": not JSON (byte " + std::to_string(e.byte) + ")";
    return CalibrationRead::Bad;
  }
  out = blvd_odometry_calibration{};
  out.struct_size = sizeof out;
  struct Field {
    const char* key;
    double* value;
  } fields[] = {{"speed_scale", &out.speed_scale},
                {"speed_scale_sigma", &out.speed_scale_sigma},
                {"yaw_rate_bias_dps", &out.yaw_rate_bias_dps},
                {"yaw_rate_bias_sigma_dps", &out.yaw_rate_bias_sigma_dps}};
  for (const Field& fd : fields) {
    if (!j.is_object() || !j.contains(fd.key) || !j[fd.key].is_number()) {
      err = path + ": no number \"" + fd.key + "\"";
      return CalibrationRead::Bad;
    }
    *fd.value = j[fd.key].get<double>();
  }
  return CalibrationRead::Loaded;
}

bool writeCalibration(const std::string& path, const blvd_odometry_calibration& cal, std::string& err) {
  const nlohmann::json j = {{"speed_scale", cal.speed_scale},
                            {"speed_scale_sigma", cal.speed_scale_sigma},
                            {"yaw_rate_bias_dps", cal.yaw_rate_bias_dps},
                            {"yaw_rate_bias_sigma_dps", cal.yaw_rate_bias_sigma_dps}};
  const std::string part = path + ".part";
  {
    std::ofstream f(part, std::ios::trunc);
    f << j.dump(2) << "\n";
    f.flush();
    if (!f) {
      err = part + ": cannot write";
      return false;
    }
  }
  if (std::rename(part.c_str(), path.c_str()) != 0) {
    err = path + ": " + std::strerror(errno);
    std::remove(part.c_str());
    return false;
  }
  return true;
}

}  // namespace vcan_drive
