// What the runtime tests share: a small descriptor on the test package, a
// runtime destroyed at scope exit, and the stats read through the C API.
#pragma once
#include <gtest/gtest.h>

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

}  // namespace blvd_test
