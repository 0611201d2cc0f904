// A small runtime on the fixture package (BLVD_TEST_PACKAGE) for tests that
// track through the C API and do not look at frames.
#pragma once

#include <gtest/gtest.h>

#include "blvd/blvd.h"

namespace blvd::test {

// Null (with a test failure naming why) when the runtime cannot be created.
inline blvd_runtime* createTrackingRuntime(int width = 64, int height = 64) {
  blvd_runtime_desc desc{};
  desc.struct_size = sizeof desc;
  desc.package_path = BLVD_TEST_PACKAGE;
  desc.width = width;
  desc.height = height;
  blvd_runtime* rt = nullptr;
  EXPECT_EQ(blvd_runtime_create(&desc, &rt), BLVD_OK) << blvd_last_error(nullptr);
  return rt;
}

}  // namespace blvd::test
