// Helpers shared by the CAN adapter tests: test data paths and zstd.
#pragma once

#include <zstd.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace blvd::can::test {

inline std::string dataPath(const std::string& rel) { return std::string(BLVD_TEST_DATA_DIR) + "/can/" + rel; }

// ../shared/data next to the checkout; BLVD_SHARED_DATA overrides. Only for data
// that must not be copied into the repository (the GPL Scion log).
inline std::string sharedDataPath(const std::string& rel) {
  const char* env = std::getenv("BLVD_SHARED_DATA");
  return std::string(env && *env ? env : BLVD_SHARED_DATA_DIR) + "/" + rel;
}

inline bool exists(const std::string& path) { return std::ifstream(path).good(); }

inline std::string readFile(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error(path + ": cannot open");
  std::ostringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// Decompresses a whole .zst file into memory (streaming, so the frame need not record its size).
inline std::string readZstd(const std::string& path) {
  const std::string in = readFile(path);
  std::string out;
  ZSTD_DStream* ds = ZSTD_createDStream();
  ZSTD_initDStream(ds);
  ZSTD_inBuffer ib{in.data(), in.size(), 0};
  std::vector<char> buf(ZSTD_DStreamOutSize());
  size_t ret = 1;
  while (ib.pos < ib.size) {
    ZSTD_outBuffer ob{buf.data(), buf.size(), 0};
    ret = ZSTD_decompressStream(ds, &ob, &ib);
    if (ZSTD_isError(ret)) {
      ZSTD_freeDStream(ds);
      throw std::runtime_error(path + ": " + ZSTD_getErrorName(ret));
    }
    out.append(buf.data(), ob.pos);
  }
  ZSTD_freeDStream(ds);
  if (ret != 0) throw std::runtime_error(path + ": truncated zstd frame");
  return out;
}

// The comma2k19 RAV4 candump log (tests/data/can, stored zstd-compressed).
inline const std::string& comma2k19Candump() {
  static const std::string log = readZstd(dataPath("comma2k19_rav4_seg40_candump.log.zst"));
  return log;
}

}  // namespace blvd::can::test
