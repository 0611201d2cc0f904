// A runtime on a package served over HTTP when the link is not there: offline
// it draws its cache and never waits for what is not cached; a start with the
// server gone opens from the table mirror; a cache a killed process left
// (a torn entry, a flipped byte, a temporary) is reopened, verified and
// repaired; a package replaced on the server mid-drive is noticed, never
// mixed in, and the next start rebuilds the cache for it.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <sys/wait.h>

#include "package/reader.h"
#include "package/writer.h"
#include "remote_drive.h"

using namespace blvd_test;
namespace fs = std::filesystem;

namespace {

// Drives `dr` from `url` into `cache` (every pose drawn whole).
void fill(const std::string& url, const std::string& cache, const Drive& dr) {
  const blvd_runtime_desc d = RemoteDriveTest::urlDescFor(url, cache);
  Rt r;
  ASSERT_EQ(blvd_runtime_create(&d, &r.rt), BLVD_OK) << blvd_last_error(nullptr);
  ASSERT_EQ(blvd_set_route(r.rt, dr.cells.data(), dr.cells.size()), BLVD_OK);
  for (const DrivePose& p : dr.poses) wholeFrame(r.rt, p, d);
}

// The test package again, with other META bytes: another package (another
// identity) with the same blobs.
void writeNewVersion(const std::string& path) {
  const blvd::package::PackageReader old = blvd::package::PackageReader::openOrThrow(BLVD_TEST_PACKAGE);
  blvd::package::PackageWriter w;
  w.setHeader(old.header());
  for (const blvd::package::SectionInfo& s : old.sections()) {
    if (s.tag == blvd::package::kSectionBlobIndex || s.tag == blvd::package::kSectionBlobData ||
        s.tag == blvd::package::kSectionTablePages)
      continue;  // the writer makes these
    const blvd::package::Span b = old.section(s.tag);
    std::vector<uint8_t> bytes(b.data, b.data + b.size);
    if (s.tag == blvd::package::kSectionMeta) bytes.push_back(' ');
    w.addSection(s.tag, std::move(bytes));
  }
  for (uint32_t i = 0; i < old.blobCount(); ++i) {
    blvd::package::Span b;
    std::string err;
    ASSERT_EQ(old.blob(i, b, err), blvd::core::Status::Ok) << err;
    const blvd::package::BlobInfo& info = old.blobInfo(i);  // copied as stored, compressed or not
    w.addStoredBlob({std::vector<uint8_t>(b.data, b.data + b.size), info.flags, info.contents_size});
  }
  w.write(path + ".new");
  // nginx's ETag is the file's mtime (seconds) and size: a replacement within
  // the same second and of the same size would keep it.
  fs::last_write_time(path + ".new", fs::last_write_time(path) + std::chrono::seconds(10));
  fs::rename(path + ".new", path);
}

}  // namespace

TEST_F(RemoteDriveTest, OfflineDrawsTheCacheAndNeverWaitsForTheRest) {
  const Drive dr = impostorDrive(12, 15.0);
  const std::string url = nginx_->url("/monaco.blvd"), cache = work_ + "/offline";
  const Drive first{{dr.cells.begin(), dr.cells.begin() + 3}, {}};
  Drive head = first;
  for (const DrivePose& p : dr.poses)
    if (std::find(head.cells.begin(), head.cells.end(), p.cell) != head.cells.end()) head.poses.push_back(p);
  fill(url, cache, head);
  // The server gone: an online start opens from the mirror after the link gives up.
  const std::string gone = "http://127.0.0.1:" + std::to_string(blvd::test::freePort()) + "/monaco.blvd";
  for (const uint32_t mode : {uint32_t(BLVD_LINK_OFFLINE), uint32_t(BLVD_LINK_ONLINE)}) {
    blvd_runtime_desc d = urlDescFor(gone, cache);
    d.link_mode = mode;
    Rt r;
    ASSERT_EQ(blvd_runtime_create(&d, &r.rt), BLVD_OK) << blvd_last_error(nullptr);
    ASSERT_EQ(blvd_set_route(r.rt, dr.cells.data(), dr.cells.size()), BLVD_OK);
    wholeFrame(r.rt, head.poses.front(), d);  // cached: drawn
    const DrivePose& far = dr.poses.back();
    ASSERT_EQ(std::count(head.cells.begin(), head.cells.end(), far.cell), 0);
    for (int k = 0; k < 5; ++k) EXPECT_TRUE(render(r.rt, far).flags & BLVD_FRAME_DEGRADED);  // never waited for
    EXPECT_EQ(blvd_wait_resident(r.rt, 300), BLVD_ERR_TIMEOUT);
    EXPECT_EQ(stats(r.rt).load_errors, 0u);
  }
  // Offline on a live server, then online: the missing cell comes.
  blvd_runtime_desc d = urlDescFor(url, cache);
  d.link_mode = BLVD_LINK_OFFLINE;
  Rt r;
  ASSERT_EQ(blvd_runtime_create(&d, &r.rt), BLVD_OK) << blvd_last_error(nullptr);
  ASSERT_EQ(blvd_set_route(r.rt, dr.cells.data(), dr.cells.size()), BLVD_OK);
  const uint64_t before = stats(r.rt).link_requests;
  EXPECT_TRUE(render(r.rt, dr.poses.back()).flags & BLVD_FRAME_DEGRADED);
  EXPECT_EQ(blvd_wait_resident(r.rt, 300), BLVD_ERR_TIMEOUT);
  EXPECT_EQ(stats(r.rt).link_requests, before);  // offline: nothing asked of the server
  EXPECT_EQ(blvd_set_link_mode(r.rt, BLVD_LINK_ONLINE), BLVD_OK);
  EXPECT_EQ(blvd_set_link_mode(r.rt, blvd_link_mode(7)), BLVD_ERR_INVALID_ARG);
  wholeFrame(r.rt, dr.poses.back(), d);
  EXPECT_GT(stats(r.rt).link_requests, before);
}

TEST_F(RemoteDriveTest, ACacheAKilledProcessLeftIsVerifiedAndRepaired) {
  const Drive dr = impostorDrive(8, 15.0);
  const std::string url = nginx_->url("/monaco.blvd"), cache = work_ + "/killed";
  const pid_t child = ::fork();
  if (child == 0) {  // this test binary again, driving until killed (a fresh process: no GL state forked)
    ::setenv("BLVD_FILL_URL", url.c_str(), 1);
    ::setenv("BLVD_FILL_CACHE", cache.c_str(), 1);
    ::execl("/proc/self/exe", "test_remote_offline", "--gtest_filter=RemoteDriveChild.FillsACacheUntilKilled",
            static_cast<char*>(nullptr));
    ::_exit(127);
  }
  // Killed once the cache holds a few blobs, perhaps mid-write.
  for (int i = 0; i < 600 && (!fs::exists(cache + "/blobs") || diskBytes(cache + "/blobs") < (300u << 10)); ++i)
    ::usleep(50000);
  ::kill(child, SIGKILL);
  ::waitpid(child, nullptr, 0);
  std::vector<fs::path> entries;
  for (const auto& f : fs::recursive_directory_iterator(cache + "/blobs"))
    if (f.path().extension() == ".blob") entries.push_back(f.path());
  ASSERT_GE(entries.size(), 3u);
  fs::resize_file(entries[0], fs::file_size(entries[0]) / 2);  // torn
  {
    std::fstream f(entries[1], std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(100);
    f.put('\x5A');  // a flipped byte
  }
  std::ofstream(entries[2].string() + ".tmp") << "half a write";
  {  // a table page of the mirror, fetched or a hole: a wrong byte either way
    const blvd::package::PackageReader pkg = blvd::package::PackageReader::openOrThrow(BLVD_TEST_PACKAGE);
    std::fstream f(cache + "/tables.blvd", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(std::streamoff(pkg.section(blvd::package::kSectionGraph).offset + 100));
    f.put('\x5A');
  }
  const blvd_runtime_desc dl = localDesc(), du = urlDescFor(url, cache);
  Rt local, remote;
  ASSERT_EQ(blvd_runtime_create(&dl, &local.rt), BLVD_OK) << blvd_last_error(nullptr);
  ASSERT_EQ(blvd_runtime_create(&du, &remote.rt), BLVD_OK) << blvd_last_error(nullptr);
  for (blvd_runtime* rt : {local.rt, remote.rt}) ASSERT_EQ(blvd_set_route(rt, dr.cells.data(), dr.cells.size()), BLVD_OK);
  for (size_t i = 0; i < dr.poses.size(); ++i)
    EXPECT_TRUE(wholeFrame(local.rt, dr.poses[i], dl) == wholeFrame(remote.rt, dr.poses[i], du)) << "pose " << i;
  const blvd_stats s = stats(remote.rt);
  EXPECT_EQ(s.load_errors, 0u);
  EXPECT_GT(s.cache_hits, 0u);  // what was whole was used
  EXPECT_FALSE(fs::exists(entries[2].string() + ".tmp"));
}

TEST_F(RemoteDriveTest, APackageReplacedOnTheServerMidDriveIsNoticedAndNeverMixed) {
  const Drive dr = impostorDrive(60, 15.0);  // longer than the link prefetch's 400 m: cells are fetched after the swap
  fs::copy_file(BLVD_TEST_PACKAGE, work_ + "/www/swap.blvd", fs::copy_options::overwrite_existing);
  const std::string url = nginx_->url("/swap.blvd"), cache = work_ + "/swap";
  const blvd_runtime_desc dl = localDesc(), du = urlDescFor(url, cache);
  Rt local, remote;
  ASSERT_EQ(blvd_runtime_create(&dl, &local.rt), BLVD_OK) << blvd_last_error(nullptr);
  ASSERT_EQ(blvd_runtime_create(&du, &remote.rt), BLVD_OK) << blvd_last_error(nullptr);
  for (blvd_runtime* rt : {local.rt, remote.rt}) ASSERT_EQ(blvd_set_route(rt, dr.cells.data(), dr.cells.size()), BLVD_OK);
  const size_t half = dr.poses.size() / 2;
  for (size_t i = 0; i < half; ++i)
    EXPECT_TRUE(wholeFrame(local.rt, dr.poses[i], dl) == wholeFrame(remote.rt, dr.poses[i], du)) << "pose " << i;
  writeNewVersion(work_ + "/www/swap.blvd");
  for (size_t i = half; i < dr.poses.size(); ++i) render(remote.rt, dr.poses[i]);
  for (int k = 0; k < 200 && !stats(remote.rt).package_changed; ++k) {
    render(remote.rt, dr.poses.back());
    ::usleep(20000);
  }
  const blvd_stats s = stats(remote.rt);
  EXPECT_EQ(s.package_changed, 1u);
  EXPECT_EQ(s.load_errors, 0u);  // nothing of the new package reached a decode
  // What is cached still draws as the old package did.
  EXPECT_TRUE(wholeFrame(local.rt, dr.poses[0], dl) == wholeFrame(remote.rt, dr.poses[0], du));
  blvd_runtime_destroy(remote.rt);  // one runtime per cache folder at a time
  remote.rt = nullptr;
  Rt again;  // the next start: the new package, its own cache
  ASSERT_EQ(blvd_runtime_create(&du, &again.rt), BLVD_OK) << blvd_last_error(nullptr);
  ASSERT_EQ(blvd_set_route(again.rt, dr.cells.data(), dr.cells.size()), BLVD_OK);
  wholeFrame(again.rt, dr.poses[0], du);
  const blvd_stats a = stats(again.rt);
  EXPECT_GE(a.link_requests, 3u);  // the first 16 KiB, the new package's page CRCs and blob index, its pages and blobs
  EXPECT_GT(a.link_table_bytes, 16384u);
  size_t identities = 0;
  for (const auto& e : fs::directory_iterator(cache + "/blobs")) identities += e.is_directory();
  EXPECT_EQ(identities, 1u);  // the old package's blobs are gone
}

// The child of ACacheAKilledProcessLeftIsVerifiedAndRepaired (skipped when
// run on its own): drives from BLVD_FILL_URL into BLVD_FILL_CACHE, then waits
// to be killed.
TEST(RemoteDriveChild, FillsACacheUntilKilled) {
  const char* url = std::getenv("BLVD_FILL_URL");
  const char* cache = std::getenv("BLVD_FILL_CACHE");
  if (!url || !cache) GTEST_SKIP() << "the killed-process test's child";
  fill(url, cache, impostorDrive(8, 15.0));
  for (;;) ::pause();
}
