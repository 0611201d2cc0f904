#include "calibration.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>

#include <nlohmann/json.hpp>

namespace vcan_drive {

namespace {
struct Field {
  const char* key;
  double* value;
};

// Every field a number; false with `err` naming the first that is not.
template <size_t N>
bool readNumbers(const nlohmann::json& j, const Field (&fields)[N], const std::string& where, std::string& err) {
  for (const Field& fd : fields) {
    if (!j.is_object() || !j.contains(fd.key) || !j[fd.key].is_number()) {
      err = where + "no number \"" + fd.key + "\"";
      return false;
    }
    *fd.value = j[fd.key].get<double>();
  }
  return true;
}
}  // namespace

CalibrationRead readCalibration(const std::string& path, KeyOffState& state, std::string& err) {
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
  state = KeyOffState{};
  blvd_odometry_calibration& cal = state.calibration;
  cal.struct_size = sizeof cal;
  const Field fields[] = {{"speed_scale", &cal.speed_scale},
                          {"speed_scale_sigma", &cal.speed_scale_sigma},
                          {"yaw_rate_bias_dps", &cal.yaw_rate_bias_dps},
                          {"yaw_rate_bias_sigma_dps", &cal.yaw_rate_bias_sigma_dps}};
  if (!readNumbers(j, fields, path + ": ", err)) return CalibrationRead::Bad;
  if (j.contains("start_pose")) {
    blvd_start_pose& sp = state.pose;
    sp.struct_size = sizeof sp;
    const Field pose[] = {{"lat", &sp.lat},
                          {"lon", &sp.lon},
                          {"heading_deg", &sp.heading_deg},
                          {"sigma_m", &sp.sigma_m},
                          {"heading_sigma_deg", &sp.heading_sigma_deg}};
    if (!readNumbers(j["start_pose"], pose, path + ": start_pose: ", err)) return CalibrationRead::Bad;
    state.has_pose = true;
  }
  return CalibrationRead::Loaded;
}

bool writeCalibration(const std::string& path, const KeyOffState& state, std::string& err) {
  const blvd_odometry_calibration& cal = state.calibration;
  nlohmann::json j = {{"speed_scale", cal.speed_scale},
                      {"speed_scale_sigma", cal.speed_scale_sigma},
                      {"yaw_rate_bias_dps", cal.yaw_rate_bias_dps},
                      {"yaw_rate_bias_sigma_dps", cal.yaw_rate_bias_sigma_dps}};
  if (state.has_pose) {
    const blvd_start_pose& sp = state.pose;
    j["start_pose"] = {{"lat", sp.lat},
                       {"lon", sp.lon},
                       {"heading_deg", sp.heading_deg},
                       {"sigma_m", sp.sigma_m},
                       {"heading_sigma_deg", sp.heading_sigma_deg}};
  }
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
