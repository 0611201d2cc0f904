// Fuzz target for the bake's DEM reader (bake/dem.h) on zipped SRTM tiles
// (libzip): any input must give a tile or fail with core::Error naming the
// file, never crash; a tile that parses has n x n finite heights and no void.
// The same bytes are also read as a bare .hgt (the size check) and as a small
// grid of samples whose voids are filled (see voids() below).
//
// Seeds: set BLVD_FUZZ_SEED_DIR and the target writes small zips there (an
// entry of the wrong size, an entry that is no .hgt, two .hgt entries): a
// whole tile is 2.9 MB unzipped, too slow an input to mutate, and the unit
// tests (tests/bake/test_dem.cpp) read real ones.
#include <zip.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "bake/dem.h"
#include "core/status.h"

namespace {

void writeZip(const std::filesystem::path& path, const std::vector<std::pair<std::string, std::string>>& entries) {
  int err = 0;
  zip_t* z = zip_open(path.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &err);
  if (!z) return;
  for (const auto& [name, text] : entries) {
    zip_source_t* s = zip_source_buffer(z, text.data(), text.size(), 0);
    if (s && zip_file_add(z, name.c_str(), s, ZIP_FL_OVERWRITE) < 0) zip_source_free(s);
  }
  zip_close(z);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  const char* dir = std::getenv("BLVD_FUZZ_SEED_DIR");
  if (!dir || !*dir) return 0;
  std::filesystem::create_directories(dir);
  const std::filesystem::path d(dir);
  writeZip(d / "short.zip", {{"N43E007.hgt", std::string(64, '\x01')}});
  writeZip(d / "readme.zip", {{"readme.txt", "SRTM3 N43E007"}});
  writeZip(d / "two.zip", {{"N43E007.hgt", "ab"}, {"N44E007.hgt", "cd"}});
  // A 7 x 7 grid, every third sample a void (-32768), the others 16 and 300 m.
  std::ofstream(d / "voids.bin", std::ios::binary) << std::string("\x05\x80\x00\x00\x10\x01\x2c", 7);
  return 0;
}

namespace {

// The zipped tile, as `blvd bake --dem` reads it.
void zipped(const std::vector<uint8_t>& bytes) {
  blvd::bake::DemTile t;
  try {
    t = blvd::bake::parseDemFile(bytes, "N43E007.hgt.zip");
  } catch (const blvd::core::Error& e) {
    if (std::string(e.what()).rfind("N43E007.hgt.zip: ", 0) != 0) std::abort();
    return;
  }
  if (t.n < 2 || t.h.size() != size_t(t.n) * size_t(t.n)) std::abort();
  for (const float h : t.h)
    if (!std::isfinite(h) || h == -32768.f) std::abort();
}

// The same bytes as a bare .hgt: a tile is 2.9 MB, so this reaches the size
// check, not the samples; those are fuzzed below.
void bare(const std::vector<uint8_t>& bytes) {
  try {
    (void)blvd::bake::parseDemFile(bytes, "S12W077.hgt");
    if (bytes.size() != 2ull * 1201 * 1201 && bytes.size() != 2ull * 3601 * 3601) std::abort();
  } catch (const blvd::core::Error& e) {
    if (std::string(e.what()).rfind("S12W077.hgt: ", 0) != 0) std::abort();
  }
}

// The void filling on a small grid: n from the first byte, the samples the
// input's big-endian int16 pairs, repeated to fill it. Every void is filled
// with a value between the valid samples' least and greatest (a weighted mean
// of them), the count is right, and a grid of voids alone is an error.
void voids(const uint8_t* data, size_t size) {
  if (size < 3) return;
  const int n = 2 + data[0] % 40;
  const size_t pairs = (size - 1) / 2;
  std::vector<float> h(size_t(n) * size_t(n));
  uint32_t expect = 0;
  float lo = INFINITY, hi = -INFINITY;
  for (size_t i = 0; i < h.size(); ++i) {
    const uint8_t* p = data + 1 + 2 * (i % pairs);
    h[i] = float(int16_t(uint16_t(p[0]) << 8 | p[1]));
    if (h[i] == -32768.f) {
      ++expect;
    } else {
      lo = std::min(lo, h[i]);
      hi = std::max(hi, h[i]);
    }
  }
  uint32_t filled = 0;
  try {
    filled = blvd::bake::fillVoids(h, n, -32768.f, "grid");
  } catch (const blvd::core::Error&) {
    if (expect != h.size()) std::abort();
    return;
  }
  if (filled != expect) std::abort();
  for (const float v : h)
    if (!std::isfinite(v) || v < lo - 0.01f || v > hi + 0.01f) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::vector<uint8_t> bytes(data, data + size);
  zipped(bytes);
  bare(bytes);
  voids(data, size);
  return 0;
}
