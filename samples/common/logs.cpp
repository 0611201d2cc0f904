#include "common/logs.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>

namespace samples {

JsonLines::~JsonLines() {
  if (f_) std::fclose(f_);
}

bool JsonLines::open(const std::string& path, std::string& err) {
  if (path.empty()) return true;
  f_ = std::fopen(path.c_str(), "w");
  if (!f_) err = path + ": " + std::strerror(errno);
  path_ = path;
  return f_ != nullptr;
}

void JsonLines::pose(const blvd_pose& p) {
  if (!f_) return;
  const long long cell = p.cell == UINT32_MAX ? -1 : static_cast<long long>(p.cell);
  auto finite = [](double v) { return std::isfinite(v) ? v : 0.0; };
  std::fprintf(f_,
               "{\"t\":%.6f,\"x\":%.3f,\"y\":%.3f,\"heading\":%.3f,\"speed\":%.6f,\"cell\":%lld,\"flags\":%u,"
               "\"camera\":[%.3f,%.3f,%.3f,%.3f,%.3f]}\n",
               p.t, finite(p.x), finite(p.y), p.heading_deg, p.speed_mps, cell, p.flags, finite(p.camera_x),
               finite(p.camera_y), finite(p.camera_z), finite(p.camera_heading_deg), finite(p.camera_pitch_deg));
}

void JsonLines::odometry(const blvd_odometry& o, uint32_t frame_id) {
  if (!f_) return;
  // %.9g keeps the decoded values exact to well below the 1e-6 the test asks.
  std::fprintf(f_,
               "{\"t\":%.6f,\"id\":%u,\"speed\":%.9g,\"yaw_rate\":%.9g,\"wheels\":[%.9g,%.9g,%.9g,%.9g],\"flags\":%u}\n",
               o.t, frame_id, o.speed_mps, o.yaw_rate_dps, o.wheel_speeds_mps[0], o.wheel_speeds_mps[1],
               o.wheel_speeds_mps[2], o.wheel_speeds_mps[3], o.flags);
}

bool JsonLines::close(std::string& err) {
  if (!f_) return true;
  const bool ok = std::fflush(f_) == 0 && !std::ferror(f_);
  if (std::fclose(f_) != 0 || !ok) {
    err = path_ + ": write failed";
    f_ = nullptr;
    return false;
  }
  f_ = nullptr;
  return true;
}

void noteCell(std::vector<uint32_t>& cells, const blvd_pose& p) {
  if (!(p.flags & BLVD_POSE_MATCHED) || p.cell == UINT32_MAX) return;
  if (cells.empty() || cells.back() != p.cell) cells.push_back(p.cell);
}

double percentile(std::vector<double> v, double pct) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t rank = static_cast<size_t>(std::ceil(pct / 100.0 * static_cast<double>(v.size())));
  return v[std::min(v.size() - 1, rank ? rank - 1 : 0)];
}

void addRenderStats(nlohmann::json& j, const RenderStats& r) {
  j["rendered_frames"] = r.frames;
  j["blank_frames"] = r.blank;
  j["uniform_frames"] = r.uniform;
  j["degraded_frames"] = r.degraded;
  j["off_map_frames"] = r.off_map;
  j["png_written"] = r.written;
  j["frame_ms_p50"] = percentile(r.frame_ms, 50);
  j["frame_ms_p95"] = percentile(r.frame_ms, 95);
  j["frame_ms_p99"] = percentile(r.frame_ms, 99);
}

bool writeStats(const std::string& path, const nlohmann::json& j) {
  if (path.empty()) return true;
  std::ofstream out(path);
  out << j.dump(2) << "\n";
  return static_cast<bool>(out.flush());
}

}  // namespace samples
