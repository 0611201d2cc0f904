// RemotePackage from several threads at once, as the runtime uses it: the
// loader's two threads fetching cells (foreground), the link prefetch
// fetching ahead (background), the render thread reading stats, asking
// what is cached and pinning. Every blob arrives whole and equal to the local
// reader's; run under ThreadSanitizer by packaging/scripts/test.sh.
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <thread>

#include "package/reader.h"
#include "remote/remote_package.h"
#include "servers.h"

using namespace blvd;
namespace fs = std::filesystem;

TEST(RemoteThreads, LoadersPrefetchAndTheRenderThreadShareOnePackage) {
  const std::string work = (fs::temp_directory_path() / ("blvd-rthreads-" + std::to_string(::getpid()))).string();
  fs::remove_all(work);
  fs::create_directories(work + "/www");
  fs::create_directories(work + "/nginx");
  fs::copy_file(BLVD_TEST_PACKAGE, work + "/www/city.blvd");
  test::ServerProcess nginx;
  std::string why;
  ASSERT_TRUE(nginx.startNginx(work + "/nginx", work + "/www", 1000000, why)) << why;
  const package::PackageReader local = package::PackageReader::openOrThrow(BLVD_TEST_PACKAGE);
  remote::RemoteOptions opt;
  opt.cache_path = work + "/cache";
  opt.cache_bytes = 64ull << 20;
  remote::RemotePackage r;
  std::string err;
  ASSERT_EQ(r.open(nginx.url("/city.blvd"), opt, err), core::Status::Ok) << err;
  const uint32_t n = std::min<uint32_t>(r.blobCount(), 120);
  std::atomic<bool> done{false};
  std::atomic<int> wrong{0};
  auto loader = [&](uint32_t first) {
    std::string e;
    std::vector<uint8_t> bytes;
    for (uint32_t i = first; i < n; i += 2) {
      const uint32_t ids[] = {i, (i + 7) % n};
      if (r.fetchBlobs(ids, 2, e) != core::Status::Ok || r.blob(i, bytes, e) != core::Status::Ok) {
        ++wrong;
        continue;
      }
      package::Span s;
      if (local.blob(i, s, e) != core::Status::Ok || bytes != std::vector<uint8_t>(s.data, s.data + s.size)) ++wrong;
    }
  };
  std::thread a(loader, 0u), b(loader, 1u);
  std::thread prefetch([&] {
    std::vector<uint32_t> ids(n);
    for (uint32_t i = 0; i < n; ++i) ids[i] = n - 1 - i;
    std::string e;
    if (r.fetchBlobs(ids.data(), ids.size(), e, true) != core::Status::Ok) ++wrong;
  });
  std::thread render([&] {
    uint64_t seen = 0;
    while (!done.load()) {
      const remote::RemoteStats s = r.stats();
      if (s.link.requests < seen || s.cache_bytes > opt.cache_bytes) ++wrong;
      seen = s.link.requests;
      r.pin({0, 1, 2});
      (void)r.cached(3);
      (void)r.changed();
    }
  });
  a.join(), b.join(), prefetch.join();
  done = true;
  render.join();
  EXPECT_EQ(wrong.load(), 0);
  for (uint32_t i = 0; i < n; ++i) EXPECT_TRUE(r.cached(i)) << "blob " << i;
  nginx.stop();
  fs::remove_all(work);
}
