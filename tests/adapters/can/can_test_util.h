// Helpers shared by the CAN adapter tests: test data paths and zstd.
#pragma once

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/test_files.h"

namespace blvd::can::test {

inline std::string dataPath(const std::string& rel) { return std::string(BLVD_TEST_DATA_DIR) + "/can/" + rel; }

// ../shared/data next to the checkout; BLVD_SHARED_DATA overrides. Only for data
// that must not be copied into the repository (the GPL Scion log).
inline std::string sharedDataPath(const std::string& rel) {
  const char* env = std::getenv("BLVD_SHARED_DATA");
  return std::string(env && *env ? env : BLVD_SHARED_DATA_DIR) + "/" + rel;
}

inline bool exists(const std::string& path) { return std::ifstream(path).good(); }

using blvd::test::readFile;
using blvd::test::readZstd;

// The comma2k19 RAV4 candump log (tests/data/can, stored zstd-compressed).
inline const std::string& comma2k19Candump() {
  static const std::string log = readZstd(dataPath("comma2k19_rav4_seg40_candump.log.zst"));
  return log;
}

}  // namespace blvd::can::test
