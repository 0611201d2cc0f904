// The disk cache: never over its bytes, least recently used out first but
// never a pinned blob, CRC checked in and out, another package's blobs
// removed, whole across a restart (a killed writer's temporary and a
// truncated entry dropped, use order kept), a refused write loses nothing.
#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <random>

#include <sys/resource.h>

#include "package/format.h"
#include "remote/disk_cache.h"

using namespace blvd;
namespace fs = std::filesystem;

namespace {

struct Blob {
  std::vector<uint8_t> bytes;
  uint32_t crc = 0;
};

Blob blobOf(size_t n, uint32_t seed) {
  Blob b;
  std::mt19937 rng(seed);
  b.bytes.resize(n);
  for (auto& x : b.bytes) x = uint8_t(rng());
  b.crc = package::crc32c(b.bytes.data(), n);
  return b;
}

class Cache : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = (fs::temp_directory_path() / ("blvd-cache-" + std::to_string(::getpid()))).string();
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  void open(remote::DiskCache& c, uint64_t max, const std::string& id = "aa11") {
    std::string err;
    ASSERT_EQ(c.open(dir_, max, id, err), core::Status::Ok) << err;
  }
  bool put(remote::DiskCache& c, uint32_t i, const Blob& b) { return c.put(i, b.crc, b.bytes.data(), b.bytes.size()); }
  std::string dir_;
};

constexpr uint64_t H = remote::DiskCache::kHeaderBytes;

}  // namespace

TEST_F(Cache, NeverMoreThanItsBytesAndLeastRecentlyUsedGoesFirst) {
  remote::DiskCache c;
  open(c, 10 * (1000 + H));
  std::vector<Blob> blobs;
  for (uint32_t i = 0; i < 40; ++i) blobs.push_back(blobOf(500 + 37 * (i % 30), i));
  std::mt19937 rng(3);
  std::vector<uint8_t> out;
  for (int step = 0; step < 400; ++step) {
    const uint32_t i = rng() % 40;
    if (!c.get(i, blobs[i].crc, out)) EXPECT_TRUE(put(c, i, blobs[i]));
    else EXPECT_EQ(out, blobs[i].bytes);
    ASSERT_LE(c.bytes(), c.maxBytes()) << "after step " << step;
    uint64_t on_disk = 0;
    for (const auto& f : fs::recursive_directory_iterator(dir_)) on_disk += f.is_regular_file() ? f.file_size() : 0;
    ASSERT_EQ(on_disk, c.bytes());
  }
  EXPECT_GT(c.stats().evictions, 0u);
  // LRU: fill with 0..9 (each 1000 bytes), touch 0, add 10: 1 goes, 0 stays.
  remote::DiskCache d;
  fs::remove_all(dir_);
  open(d, 10 * (1000 + H));
  std::vector<Blob> same;
  for (uint32_t i = 0; i < 11; ++i) same.push_back(blobOf(1000, 100 + i)), put(d, i, same[i]);
  EXPECT_FALSE(d.contains(0));  // 10 evicted the oldest, 0
  ASSERT_TRUE(d.get(1, same[1].crc, out));
  put(d, 0, same[0]);
  EXPECT_TRUE(d.contains(1));
  EXPECT_FALSE(d.contains(2));
}

TEST_F(Cache, PinnedBlobsStayAndWhatDoesNotFitIsNotCached) {
  remote::DiskCache c;
  open(c, 3 * (1000 + H));
  const Blob a = blobOf(1000, 1), b = blobOf(1000, 2), d = blobOf(1000, 3), e = blobOf(1000, 4);
  ASSERT_TRUE(put(c, 1, a) && put(c, 2, b) && put(c, 3, d));
  c.pin({1, 2, 3});
  EXPECT_FALSE(put(c, 4, e));  // only pinned entries: not cached, nothing evicted
  EXPECT_EQ(c.entries(), 3u);
  c.pin({1, 3});
  EXPECT_TRUE(put(c, 4, e));
  EXPECT_FALSE(c.contains(2));
  EXPECT_FALSE(put(c, 5, blobOf(4 * 1000, 5)));  // bigger than the cache
  Blob wrong = blobOf(100, 6);
  wrong.crc ^= 1;
  EXPECT_FALSE(put(c, 6, wrong));  // its CRC is not the package's: never cached
  EXPECT_EQ(c.stats().not_cached, 3u);
}

TEST_F(Cache, ABadEntryOnDiskIsDroppedNeverReturned) {
  remote::DiskCache c;
  open(c, 100000);
  const Blob a = blobOf(3000, 1);
  ASSERT_TRUE(put(c, 7, a));
  {
    std::fstream f(dir_ + "/aa11/7.blob", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(H + 1500);
    f.put(char(0x5A ^ a.bytes[1500]));
  }
  std::vector<uint8_t> out;
  EXPECT_FALSE(c.get(7, a.crc, out));
  EXPECT_TRUE(out.empty());
  EXPECT_FALSE(c.contains(7));
  EXPECT_FALSE(fs::exists(dir_ + "/aa11/7.blob"));
  EXPECT_EQ(c.stats().dropped, 1u);
}

TEST_F(Cache, ReopenedAfterAKillWithItsUseOrderAndWithoutAnotherPackagesBlobs) {
  std::vector<Blob> blobs;
  {
    remote::DiskCache c;
    open(c, 4 * (1000 + H));
    for (uint32_t i = 0; i < 4; ++i) blobs.push_back(blobOf(1000, 10 + i)), put(c, i, blobs[i]);
    std::vector<uint8_t> out;
    ASSERT_TRUE(c.get(0, blobs[0].crc, out));  // 0 is now the most recent
  }
  // What a killed process leaves: a temporary, and a truncated entry.
  std::ofstream(dir_ + "/aa11/9.blob.tmp") << "partial";
  fs::resize_file(dir_ + "/aa11/3.blob", H + 10);
  remote::DiskCache c;
  open(c, 4 * (1000 + H));
  EXPECT_EQ(c.entries(), 3u);
  EXPECT_FALSE(c.contains(3));
  EXPECT_FALSE(fs::exists(dir_ + "/aa11/9.blob.tmp"));
  EXPECT_EQ(c.stats().dropped, 2u);
  put(c, 3, blobs[3]);
  put(c, 4, blobOf(1000, 99));  // evicts the least recently used: 1, not 0
  EXPECT_TRUE(c.contains(0));
  EXPECT_FALSE(c.contains(1));
  // The package changed: its identity too; the old blobs go.
  remote::DiskCache other;
  open(other, 4 * (1000 + H), "bb22");
  EXPECT_EQ(other.entries(), 0u);
  EXPECT_FALSE(fs::exists(dir_ + "/aa11"));
  std::vector<uint8_t> out;
  EXPECT_FALSE(other.get(0, blobs[0].crc, out));
}

TEST_F(Cache, ADiskThatRefusesTheWriteLosesNothing) {
  remote::DiskCache c;
  open(c, 1 << 20);
  const Blob small = blobOf(100, 1), big = blobOf(64 * 1024, 2);
  ASSERT_TRUE(put(c, 1, small));
  // A file size limit stands in for a full disk: the write fails part-way.
  std::signal(SIGXFSZ, SIG_IGN);
  rlimit old{};
  getrlimit(RLIMIT_FSIZE, &old);
  rlimit lim = old;
  lim.rlim_cur = 4096;
  setrlimit(RLIMIT_FSIZE, &lim);
  const bool cached = put(c, 2, big);
  setrlimit(RLIMIT_FSIZE, &old);
  EXPECT_FALSE(cached);
  EXPECT_FALSE(c.contains(2));
  EXPECT_FALSE(fs::exists(dir_ + "/aa11/2.blob.tmp"));
  EXPECT_EQ(c.bytes(), H + 100);
  std::vector<uint8_t> out;
  EXPECT_TRUE(c.get(1, small.crc, out));
  EXPECT_EQ(out, small.bytes);
}

TEST_F(Cache, OpenRefusesWhatCannotBeACache) {
  remote::DiskCache c;
  std::string err;
  EXPECT_EQ(c.open(dir_, 1 << 20, "", err), core::Status::InvalidArg);
  EXPECT_EQ(c.open(dir_, 10, "aa11", err), core::Status::InvalidArg);
  EXPECT_NE(err.find("holds no entry"), std::string::npos) << err;
  std::ofstream(dir_ + "-file") << "x";
  EXPECT_EQ(c.open(dir_ + "-file", 1 << 20, "aa11", err), core::Status::Io);
  fs::remove(dir_ + "-file");
}
