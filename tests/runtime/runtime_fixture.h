// What the runtime tests share: a small descriptor on the test package, a
// runtime destroyed at scope exit, and the stats read through the C API.
#pragma once
#include <gtest/gtest.h>
#include <sys/types.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "blvd/blvd.h"

namespace blvd_test {

inline blvd_runtime_desc baseDesc() {
  blvd_runtime_desc d{};
  d.struct_size = sizeof d;
  d.package_path = BLVD_TEST_PACKAGE;
  d.width = 320;
  d.height = 192;
  return d;
}

struct Runtime {
  blvd_runtime* rt = nullptr;
  ~Runtime() { blvd_runtime_destroy(rt); }
};

inline blvd_stats statsOf(blvd_runtime* rt) {
  blvd_stats s{};
  s.struct_size = sizeof s;
  EXPECT_EQ(blvd_runtime_stats(rt, &s), BLVD_OK);
  return s;
}

// The frame at pose (x, y, heading), drawn whole: a degraded frame waits for
// its cell and is drawn again. width × height RGBA8.
inline std::vector<uint8_t> wholeFrame(blvd_runtime* rt, double x, double y, double heading_deg, uint32_t width,
                                       uint32_t height, double timeout_ms = 120000) {
  EXPECT_EQ(blvd_set_pose_local(rt, x, y, float(heading_deg), 0.f), BLVD_OK);
  blvd_frame_stats fs{};
  fs.struct_size = sizeof fs;
  EXPECT_EQ(blvd_render(rt, &fs), BLVD_OK) << blvd_last_error(rt);
  if (fs.flags & BLVD_FRAME_DEGRADED) {
    EXPECT_EQ(blvd_wait_resident(rt, timeout_ms), BLVD_OK) << blvd_last_error(rt);
    EXPECT_EQ(blvd_render(rt, &fs), BLVD_OK) << blvd_last_error(rt);
  }
  EXPECT_EQ(fs.flags & BLVD_FRAME_DEGRADED, 0u) << blvd_last_error(rt);
  std::vector<uint8_t> px(size_t(width) * height * 4);
  EXPECT_EQ(blvd_read_pixels(rt, px.data(), px.size()), BLVD_OK) << blvd_last_error(rt);
  return px;
}

// The thread of this process named `name` (blvd-loader, blvd-prefetch), or 0.
inline pid_t threadNamed(const std::string& name) {
  for (const auto& e : std::filesystem::directory_iterator("/proc/self/task")) {
    std::ifstream comm(e.path() / "comm");
    std::string got;
    std::getline(comm, got);
    if (got == name) return pid_t(std::stol(e.path().filename().string()));
  }
  return 0;
}

}  // namespace blvd_test
