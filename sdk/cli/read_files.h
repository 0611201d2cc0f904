// File helpers shared by the CLI's benchmarks and the tests (tests/common/test_files.h):
// read a whole file, and a whole zstd-compressed file (streaming, so the frame
// need not record its size).
#pragma once

#include <zstd.h>

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace blvd::cli {

inline std::string readFile(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error(path + ": cannot open");
  std::ostringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

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

}  // namespace blvd::cli
