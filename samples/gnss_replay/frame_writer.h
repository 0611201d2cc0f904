// gnss_replay's frames: one blvd_render + blvd_read_pixels per tick of the
// log's clock, written as a PNG sequence, with the per-frame numbers the stats
// JSON reports (frame time, degraded and blank frames: samples::RenderStats).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "blvd/blvd.h"
#include "common/logs.h"

namespace gnss_replay {

class FrameWriter {
 public:
  // dir: PNG folder, created; "" renders and measures without writing.
  // wait_ms: how long each frame may wait for its cell (blvd_wait_resident);
  // 0 never waits, as a live display must not. False with `err` set on failure.
  bool open(blvd_runtime* rt, uint32_t width, uint32_t height, const std::string& dir, double wait_ms,
            std::string& err);

  // Renders the tracker's camera now. False with `err` set when rendering,
  // reading back or writing failed (a cell that did not load in time is not
  // a failure: the frame is drawn degraded and counted).
  bool frame(std::string& err);

  const samples::RenderStats& stats() const { return stats_; }
  uint64_t waitTimeouts() const { return wait_timeouts_; }

 private:
  blvd_runtime* rt_ = nullptr;
  uint32_t width_ = 0, height_ = 0;
  std::string dir_;
  double wait_ms_ = 0;
  std::vector<unsigned char> rgba_;
  samples::RenderStats stats_;
  uint64_t wait_timeouts_ = 0;
};

}  // namespace gnss_replay
