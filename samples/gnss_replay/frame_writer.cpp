#include "frame_writer.h"

#include <cstdio>
#include <filesystem>

#include "common/png.h"

namespace gnss_replay {

bool FrameWriter::open(blvd_runtime* rt, uint32_t width, uint32_t height, const std::string& dir, double wait_ms,
                       std::string& err) {
  rt_ = rt;
  width_ = width;
  height_ = height;
  dir_ = dir;
  wait_ms_ = wait_ms;
  std::error_code ec;
  if (!dir.empty() && (std::filesystem::create_directories(dir, ec), ec)) {
    err = "cannot create " + dir + ": " + ec.message();
    return false;
  }
  rgba_.resize(size_t(width) * height * 4);
  return true;
}

bool FrameWriter::frame(std::string& err) {
  if (wait_ms_ > 0) {
    const blvd_status st = blvd_wait_resident(rt_, wait_ms_);
    if (st == BLVD_ERR_TIMEOUT) {
      ++wait_timeouts_;
    } else if (st != BLVD_OK) {
      err = std::string("blvd_wait_resident: ") + blvd_last_error(rt_);
      return false;
    }
  }
  blvd_frame_stats fs{};
  fs.struct_size = sizeof fs;
  if (blvd_render(rt_, &fs) != BLVD_OK || blvd_read_pixels(rt_, rgba_.data(), rgba_.size()) != BLVD_OK) {
    err = std::string("render: ") + blvd_last_error(rt_);
    return false;
  }
  stats_.frame_ms.push_back(fs.frame_ms);
  if (fs.flags & BLVD_FRAME_DEGRADED) ++stats_.degraded;
  if (samples::isBlank(rgba_.data(), width_, height_, fs.triangles)) ++stats_.blank;
  else if (samples::isUniform(rgba_.data(), width_, height_)) ++stats_.uniform;
  if (!dir_.empty()) {
    char name[32];
    std::snprintf(name, sizeof name, "/frame_%06llu.png", static_cast<unsigned long long>(stats_.frames));
    if (!samples::writePng(dir_ + name, rgba_.data(), width_, height_)) {
      err = "cannot write " + dir_ + name;
      return false;
    }
    ++stats_.written;
  }
  ++stats_.frames;
  return true;
}

}  // namespace gnss_replay
