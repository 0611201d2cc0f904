#include "frames.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "common/frame_record.h"

namespace vcan_drive {

bool Frames::open(Tracking& tracking, const std::string& dir, bool display, std::string& err) {
  tracking_ = &tracking;
  dir_ = dir;
  std::error_code ec;
  if (!dir.empty() && (std::filesystem::create_directories(dir, ec), ec)) {
    err = "cannot create " + dir + ": " + ec.message();
    return false;
  }
  rgba_.resize(size_t(tracking.width()) * tracking.height() * 4);
  if (display && !(display_ = openDisplay(tracking.width(), tracking.height(), err))) return false;
  return true;
}

bool Frames::frame(const blvd_pose* pose) {
  blvd_frame_stats fs{};
  if (tracking_->render(pose, rgba_.data(), fs) != BLVD_OK) {
    std::fprintf(stderr, "vcan_drive: render: %s\n", tracking_->lastError().c_str());
    return false;
  }
  std::string err;
  if (!samples::recordFrame(stats_, fs, rgba_.data(), tracking_->width(), tracking_->height(), dir_, err)) {
    std::fprintf(stderr, "vcan_drive: %s\n", err.c_str());
    return false;
  }
  if (display_ && !display_->show(rgba_.data())) closed_ = true;
  return true;
}

int renderRecorded(const std::string& poses_path, unsigned render_every, const std::string& stats_path,
                   Frames& frames, const volatile std::sig_atomic_t& stop) {
  std::ifstream in(poses_path);
  if (!in) {
    std::fprintf(stderr, "vcan_drive: cannot read %s\n", poses_path.c_str());
    return 2;
  }
  std::string line;
  uint64_t n = 0, valid = 0, lineno = 0;
  while (std::getline(in, line) && !stop && !frames.closed()) {
    ++lineno;
    const nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
    if (j.is_discarded() || !j.contains("x") || !j.contains("y") || !j.contains("heading") || !j.contains("flags")) {
      std::fprintf(stderr, "vcan_drive: %s:%llu: not a pose line\n", poses_path.c_str(),
                   static_cast<unsigned long long>(lineno));
      return 1;
    }
    blvd_pose p{};
    p.struct_size = sizeof p;
    p.x = j["x"].get<double>();
    p.y = j["y"].get<double>();
    p.heading_deg = j["heading"].get<double>();
    p.flags = j["flags"].get<uint32_t>();
    // The camera the live run would have drawn from: on the matched street.
    // Lines from before blvd_pose had it fall back to the fused position.
    const nlohmann::json cam = j.value("camera", nlohmann::json::array());
    const bool has_camera = cam.is_array() && cam.size() == 5;
    p.camera_x = has_camera ? cam[0].get<double>() : p.x;
    p.camera_y = has_camera ? cam[1].get<double>() : p.y;
    p.camera_heading_deg = has_camera ? cam[3].get<double>() : p.heading_deg;
    p.camera_pitch_deg = has_camera ? cam[4].get<double>() : 0.0;
    ++n;
    if (!(p.flags & BLVD_POSE_VALID)) continue;
    if (valid++ % render_every == 0 && !frames.frame(&p)) return 1;
  }
  nlohmann::json j;
  j["mode"] = "render-poses";
  j["poses"] = n;
  j["valid_poses"] = valid;
  samples::addRenderStats(j, frames.stats());
  std::printf("%s\n", j.dump().c_str());
  return samples::writeStats(stats_path, j) ? 0 : 1;
}

}  // namespace vcan_drive
