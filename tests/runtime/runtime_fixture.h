// What the runtime tests share: a small descriptor on the test package, a
// runtime destroyed at scope exit, and the stats read through the C API.
#pragma once
#include <gtest/gtest.h>
#include <sys/types.h>

#include <filesystem>
#include <fstream>
#include <string>

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
