// Fuzz target for the bake's DEM reader (bake/dem.h) on zipped SRTM tiles
// (libzip): any input must give a tile or fail with core::Error naming the
// file, never crash; a tile that parses has n x n finite heights and no void.
//
// Seeds: set BLVD_FUZZ_SEED_DIR and the target writes small zips there (an
// entry of the wrong size, an entry that is no .hgt, two .hgt entries): a
// whole tile is 2.9 MB unzipped, too slow an input to mutate, and the unit
// tests (tests/bake/test_dem.cpp) read real ones.
#include <zip.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
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
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::vector<uint8_t> bytes(data, data + size);
  blvd::bake::DemTile t;
  try {
    t = blvd::bake::parseDemFile(bytes, "N43E007.hgt.zip");
  } catch (const blvd::core::Error& e) {
    if (std::string(e.what()).rfind("N43E007.hgt.zip: ", 0) != 0) std::abort();
    return 0;
  }
  if (t.n < 2 || t.h.size() != size_t(t.n) * size_t(t.n)) std::abort();
  for (const float h : t.h)
    if (!std::isfinite(h) || h == -32768.f) std::abort();
  return 0;
}
