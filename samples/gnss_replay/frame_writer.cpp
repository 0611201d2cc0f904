#include "frame_writer.h"

#include <filesystem>

#include "common/frame_record.h"

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
  return samples::recordFrame(stats_, fs, rgba_.data(), width_, height_, dir_, err);
}

}  // namespace gnss_replay
