// What `blvd bench memory` and `blvd bench scale` share: a drive of one
// package along a route in a fresh child process of this binary (`blvd bench
// memory-drive`, which prints one JSON line: peak RSS, allocations per frame,
// table and GPU bytes, and with frame_repeat the blvd and full-model frame
// times), so that each package gets a clean process and a peak of its own.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "stream/city.h"

namespace blvd::cli {

struct MemoryOpts {  // the options of bench memory, its child and bench scale
  std::string pkg_1x, pkg_4x, route = "auto:60", size = "800x480", json_path, cells;
  uint64_t seed = 1;
  double step = 10;
  int laps = 3;
  double max_rss_diff_pct = 2.0;
  int frame_repeat = 0;  // the child: after the laps, time each pose this often in blvd and full mode
};

// The same cells, with the same geometry, must exist in the larger package
// (`blvd bake --tile` keeps tile 0 as the original); else InvalidArg.
void checkSameRoute(const stream::City& a, const stream::City& b, const std::vector<uint32_t>& route);

// Runs `exe bench memory-drive pkg --cells cells ...` and parses its JSON line.
nlohmann::json driveChild(const std::string& exe, const std::string& pkg, const std::string& cells, const MemoryOpts& o);

// This executable (/proc/self/exe), and a route as the child's --cells list.
std::string selfExe();
std::string cellList(const std::vector<uint32_t>& route);

}  // namespace blvd::cli
