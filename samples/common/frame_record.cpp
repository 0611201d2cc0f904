#include "common/frame_record.h"

#include <cstdio>

#include "common/png.h"

namespace samples {

bool recordFrame(RenderStats& stats, const blvd_frame_stats& fs, const unsigned char* rgba, uint32_t width,
                 uint32_t height, const std::string& dir, std::string& err) {
  stats.frame_ms.push_back(fs.frame_ms);
  if (fs.flags & BLVD_FRAME_DEGRADED) ++stats.degraded;
  if (fs.flags & BLVD_FRAME_OFF_MAP) ++stats.off_map;
  if (isBlank(rgba, width, height, fs.triangles)) ++stats.blank;
  else if (isUniform(rgba, width, height)) ++stats.uniform;
  if (!dir.empty()) {
    char name[32];
    std::snprintf(name, sizeof name, "/frame_%06llu.png", static_cast<unsigned long long>(stats.frames));
    if (!writePng(dir + name, rgba, width, height)) {
      err = "cannot write " + dir + name;
      return false;
    }
    ++stats.written;
  }
  ++stats.frames;
  return true;
}

}  // namespace samples
