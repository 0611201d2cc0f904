// One rendered frame counted into a sample's RenderStats and, with a folder,
// written as a PNG: what vcan_drive and gnss_replay do after each blvd_render.
#pragma once

#include <cstdint>
#include <string>

#include "blvd/blvd.h"
#include "common/logs.h"

namespace samples {

// Adds the frame's time, whether it was degraded, blank (nothing drawn, or
// black) or one colour with geometry drawn (a wall filling the view), and
// writes DIR/frame_NNNNNN.png unless `dir` is empty. False with `err` set when
// the PNG cannot be written.
bool recordFrame(RenderStats& stats, const blvd_frame_stats& fs, const unsigned char* rgba, uint32_t width,
                 uint32_t height, const std::string& dir, std::string& err);

}  // namespace samples
