// What the runtime-over-HTTP tests share: a copy of the test package served
// by a real nginx and by fault_server.py, descriptors for a runtime on the
// local file and one on a URL, frames drawn whole, and the bytes a cache
// folder holds on disk.
#pragma once
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "blvd/blvd.h"
#include "runtime/drive.h"
#include "runtime/runtime_fixture.h"
#include "servers.h"

namespace blvd_test {

// A server-side copy of the test package, nginx and the fault server over it.
class RemoteDriveTest : public ::testing::Test {
 public:
  static void SetUpTestSuite() {
    namespace fs = std::filesystem;
    work_ = (fs::temp_directory_path() / ("blvd-rdrive-" + std::to_string(::getpid()))).string();
    fs::remove_all(work_);
    for (const char* d : {"/www", "/nginx", "/fault"}) fs::create_directories(work_ + d);
    fs::copy_file(BLVD_TEST_PACKAGE, work_ + "/www/monaco.blvd");
    nginx_ = new blvd::test::ServerProcess;
    faults_ = new blvd::test::ServerProcess;
    if (!nginx_->startNginx(work_ + "/nginx", work_ + "/www", 125000, why_) ||
        !faults_->startFaultServer(work_ + "/fault", work_ + "/www", why_))
      why_ = "servers: " + why_;
  }
  static void TearDownTestSuite() {
    delete nginx_;
    delete faults_;
    std::filesystem::remove_all(work_);
  }
  void SetUp() override { ASSERT_TRUE(why_.empty()) << why_; }

  static blvd_runtime_desc localDesc() {
    blvd_runtime_desc d = baseDesc();
    d.width = 160;
    d.height = 96;
    d.mode = BLVD_MODE_BLVD;
    d.prefetch_priority = BLVD_PREFETCH_LOW;  // predictions run on a loaded CI machine too
    return d;
  }
  // `url` and `cache` must outlive the runtime made from it.
  static blvd_runtime_desc urlDesc(const std::string& url, const std::string& cache, uint64_t cache_bytes) {
    blvd_runtime_desc d = localDesc();
    d.package_path = url.c_str();
    d.cache_path = cache.c_str();
    d.cache_bytes = cache_bytes;
    return d;
  }
  static blvd_runtime_desc urlDescFor(const std::string& url, const std::string& cache) {
    return urlDesc(url, cache, 64ull << 20);
  }

  static inline std::string work_, why_;
  static inline blvd::test::ServerProcess *nginx_ = nullptr, *faults_ = nullptr;
};

using Rt = Runtime;

inline blvd_stats stats(blvd_runtime* rt) { return statsOf(rt); }

inline std::vector<uint8_t> wholeFrame(blvd_runtime* rt, const DrivePose& p, const blvd_runtime_desc& d) {
  return wholeFrame(rt, p.x, p.y, p.heading_deg, d.width, d.height);
}

// One frame at the pose, as it comes (degraded or not).
inline blvd_frame_stats render(blvd_runtime* rt, const DrivePose& p) {
  EXPECT_EQ(blvd_set_pose_local(rt, p.x, p.y, float(p.heading_deg), 0.f), BLVD_OK);
  blvd_frame_stats fs{};
  fs.struct_size = sizeof fs;
  EXPECT_EQ(blvd_render(rt, &fs), BLVD_OK) << blvd_last_error(rt);
  return fs;
}

// Does pixel i's colour differ between two RGBA8 frames?
inline bool pixelDiffers(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b, size_t i) {
  const size_t k = 4 * i;
  return a[k] != b[k] || a[k + 1] != b[k + 1] || a[k + 2] != b[k + 2];
}

// Pixels whose colour differs between two frames.
inline size_t differingPixels(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  size_t n = 0;
  for (size_t i = 0; 4 * i + 3 < a.size() && 4 * i + 3 < b.size(); ++i) n += pixelDiffers(a, b, i);
  return n;
}

// Bytes the folder takes on disk: every file's size, but what a sparse file
// (the table mirror) really holds, rounded to its blocks.
inline uint64_t diskBytes(const std::string& dir) {
  uint64_t n = 0;
  std::error_code ec;
  for (const auto& f : std::filesystem::recursive_directory_iterator(dir, ec)) {
    struct stat st {};
    if (!f.is_regular_file() || ::stat(f.path().c_str(), &st) != 0) continue;
    n += std::min<uint64_t>(uint64_t(st.st_size), uint64_t(st.st_blocks) * 512);
  }
  return n;
}

}  // namespace blvd_test
