// The samples' outputs (vcan_drive, gnss_replay): poses and decoded odometry as
// JSON lines, and the closing stats JSON. Lines are written with fixed formats
// (no JSON library on the per-frame path) and read back by tests/vcan/checks.py.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "blvd/blvd.h"

namespace samples {

// One JSON object per line to a file; a no-op when no path was given.
class JsonLines {
 public:
  ~JsonLines();
  bool open(const std::string& path, std::string& err);  // "" : disabled
  bool enabled() const { return f_ != nullptr; }
  // {"t":..,"x":..,"y":..,"heading":..,"speed":..,"cell":..,"flags":..} (cell -1: none)
  void pose(const blvd_pose& p);
  // {"t":..,"id":..,"speed":..,"yaw_rate":..,"wheels":[..],"flags":..}
  void odometry(const blvd_odometry& o, uint32_t frame_id);
  bool close(std::string& err);

 private:
  FILE* f_ = nullptr;
  std::string path_;
};

// Appends the pose's matched cell unless it is the last one: the cells in the
// order they were entered, repeats collapsed (the stats' "cells_visited").
void noteCell(std::vector<uint32_t>& cells, const blvd_pose& p);

// Percentile (0..100) by nearest rank of an unsorted sample; 0 when empty.
double percentile(std::vector<double> v, double pct);

struct RenderStats {
  // Rendered; blank (one colour and nothing drawn, or black: a failed
  // render); one colour with geometry drawn (a wall filling the view at a
  // tight corner: flat-shaded walls have no texture); PNGs written.
  uint64_t frames = 0, blank = 0, uniform = 0, written = 0;
  uint64_t degraded = 0;                        // BLVD_FRAME_DEGRADED: the current cell was not resident yet
  uint64_t off_map = 0;                         // BLVD_FRAME_OFF_MAP: the pose was off the map (sky and ground)
  std::vector<double> frame_ms;
};

// rendered_frames, blank_frames, degraded_frames, off_map_frames, png_written, frame_ms_p50/p95/p99 into `j`.
void addRenderStats(nlohmann::json& j, const RenderStats& r);
// Writes `j` (indented) to `path`; "" writes nothing. False when the write failed.
bool writeStats(const std::string& path, const nlohmann::json& j);

}  // namespace samples
