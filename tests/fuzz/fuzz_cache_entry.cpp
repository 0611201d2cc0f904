// Fuzz target for the disk cache's entries (sdk/remote/disk_cache.h), which
// a killed process, a full disk or a flipped bit may leave in any state: the
// input becomes an entry file; opening the cache and reading the entry must
// drop it or return exactly the bytes whose CRC32C the caller asked for.
//
// Seeds: set BLVD_FUZZ_SEED_DIR and the target writes a valid entry there.
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "package/format.h"
#include "remote/disk_cache.h"

namespace fs = std::filesystem;

namespace {
const std::string& cacheDir() {
  static const std::string dir = (fs::temp_directory_path() / ("blvd-fuzz-cache-" + std::to_string(::getpid()))).string();
  return dir;
}
}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  const char* dir = std::getenv("BLVD_FUZZ_SEED_DIR");
  if (!dir || !*dir) return 0;
  fs::create_directories(dir);
  blvd::remote::DiskCache c;
  std::string err;
  const std::string work = cacheDir() + "-seed";
  if (c.open(work, 1 << 20, "feed", err) != blvd::core::Status::Ok) return 0;
  const std::vector<uint8_t> blob = {'g', 'l', 'T', 'F', 2, 0, 0, 0, 42};
  c.put(5, blvd::package::crc32c(blob.data(), blob.size()), blob.data(), blob.size());
  fs::copy_file(work + "/feed/5.blob", fs::path(dir) / "entry.blob", fs::copy_options::overwrite_existing);
  fs::remove_all(work);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string dir = cacheDir();
  fs::create_directories(dir + "/feed");
  std::ofstream(dir + "/feed/5.blob", std::ios::binary).write(reinterpret_cast<const char*>(data), std::streamsize(size));
  blvd::remote::DiskCache c;
  std::string err;
  if (c.open(dir, 1 << 20, "feed", err) != blvd::core::Status::Ok) std::abort();
  const uint32_t crc = size >= 16 ? uint32_t(data[12]) | uint32_t(data[13]) << 8 | uint32_t(data[14]) << 16 |
                                        uint32_t(data[15]) << 24
                                  : 0;
  std::vector<uint8_t> out;
  if (c.get(5, crc, out) && blvd::package::crc32c(out.data(), out.size()) != crc) std::abort();
  if (c.bytes() > c.maxBytes()) std::abort();
  fs::remove_all(dir);
  return 0;
}
