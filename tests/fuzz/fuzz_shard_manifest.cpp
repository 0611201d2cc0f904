// Fuzz target for the manifest of a bake shard (SHRD section, bake/shard.h),
// which `blvd pack merge` reads from files a cluster wrote: any input must
// parse or fail with core::Error(Corrupt) naming the shard, never crash; a
// manifest that parses must write and parse back to itself.
//
// Seeds: set BLVD_FUZZ_SEED_DIR and the target writes a manifest there.
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "bake/shard.h"
#include "core/status.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  const char* dir = std::getenv("BLVD_FUZZ_SEED_DIR");
  if (!dir || !*dir) return 0;
  std::filesystem::create_directories(dir);
  blvd::bake::ShardManifest m;
  m.index = 1, m.count = 4, m.input_name = "monaco.osm.pbf", m.input_bytes = 673936;
  m.input_sha256 = std::string(64, '1'), m.options_sha256 = std::string(64, '2'), m.generator = "blvd bake 0.1.0";
  m.block_blobs = 365, m.streets = {3, 17, 40}, m.plan_streets = 12, m.plan_sha256 = std::string(64, '3');
  m.plan_costs = {10, 11.5, 9, 10}, m.blocks_drawn = 365, m.seconds = 3.5, m.cpu_seconds = 6.25;
  std::ofstream(std::filesystem::path(dir) / "manifest.json") << blvd::bake::manifestJson(m);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  blvd::bake::ShardManifest m;
  try {
    m = blvd::bake::parseManifest(text, "fuzz.blvdshard");
  } catch (const blvd::core::Error& e) {
    if (e.status() != blvd::core::Status::Corrupt || std::string(e.what()).rfind("fuzz.blvdshard: ", 0) != 0)
      std::abort();
    return 0;
  }
  const std::string again = blvd::bake::manifestJson(m);
  if (blvd::bake::manifestJson(blvd::bake::parseManifest(again, "again")) != again) std::abort();
  return 0;
}
