// A package read over HTTP from a real nginx: the same header, sections and
// blobs as the local reader, two requests to open, each blob fetched once
// then served by the disk cache (also after a restart), a package swapped on
// the server noticed and its cache rebuilt, a corrupt blob refused.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "package/reader.h"
#include "package/writer.h"
#include "remote/remote_package.h"
#include "servers.h"

using namespace blvd;
namespace fs = std::filesystem;

namespace {

std::vector<uint8_t> bytesOf(size_t n, uint8_t seed) {
  std::vector<uint8_t> v(n);
  for (size_t i = 0; i < n; ++i) v[i] = uint8_t(seed + i * 7 + (i >> 5));
  return v;
}

// A small package: three sections and `blobs` blobs of a few kB.
void writePackage(const std::string& path, int blobs, uint8_t seed) {
  package::PackageWriter w;
  package::PackageHeader h;
  h.cell_count = 4, h.block_count = uint32_t(blobs), h.origin_lat = 43.7, h.origin_lon = 7.42;
  w.setHeader(h);
  w.addSection(package::kSectionGraph, bytesOf(3000, seed));
  w.addSection(package::kSectionBlocks, bytesOf(500, seed + 1));
  w.addSection(package::kSectionMeta, bytesOf(100, seed + 2));
  for (int i = 0; i < blobs; ++i) w.addBlob(bytesOf(2000 + 100 * size_t(i), uint8_t(seed + 10 + i)));
  w.write(path + ".new");
  fs::rename(path + ".new", path);
}

class RemotePkg : public ::testing::Test {
 protected:
  void SetUp() override {
    work_ = (fs::temp_directory_path() / ("blvd-rpkg-" + std::to_string(::getpid()))).string();
    fs::remove_all(work_);
    fs::create_directories(work_ + "/www");
    fs::create_directories(work_ + "/nginx");
    writePackage(work_ + "/www/city.blvd", 6, 1);
    std::string why;
    ASSERT_TRUE(nginx_.startNginx(work_ + "/nginx", work_ + "/www", 1000000, why)) << why;
    opt_.cache_path = work_ + "/cache";
    opt_.cache_bytes = 1 << 20;
    opt_.link.backoff_s = 0.05;
  }
  void TearDown() override {
    nginx_.stop();
    fs::remove_all(work_);
  }
  std::string work_;
  test::ServerProcess nginx_;
  remote::RemoteOptions opt_;
};

}  // namespace

TEST_F(RemotePkg, ReadsWhatTheLocalReaderReadsInTwoRequestsThenFromTheCache) {
  const package::PackageReader local = package::PackageReader::openOrThrow(work_ + "/www/city.blvd");
  remote::RemotePackage r;
  std::string err;
  ASSERT_EQ(r.open(nginx_.url("/city.blvd"), opt_, err), core::Status::Ok) << err;
  // Header, directory and, in a package this small, every table: the first 16 KiB, one request.
  EXPECT_EQ(r.stats().link.requests, 1u);
  EXPECT_GE(r.sections().back().offset, 4096u);  // BDAT, after the tables ...
  EXPECT_EQ(r.stats().mirror_bytes, 16384u);     // ... all of them in the mirror, with the first read's blob bytes
  EXPECT_EQ(r.fileSize(), local.fileSize());
  EXPECT_EQ(r.header().origin_lat, local.header().origin_lat);
  EXPECT_EQ(r.header().cell_count, 4u);
  ASSERT_EQ(r.blobCount(), local.blobCount());
  std::vector<uint8_t> s;
  ASSERT_EQ(r.section(package::kSectionGraph, s, err), core::Status::Ok) << err;
  const package::Span ls = local.section(package::kSectionGraph);
  EXPECT_EQ(s, std::vector<uint8_t>(ls.data, ls.data + ls.size));
  for (uint32_t i = 0; i < r.blobCount(); ++i) {
    std::vector<uint8_t> b;
    bool cached = true;
    ASSERT_EQ(r.blob(i, b, err, &cached), core::Status::Ok) << err;
    EXPECT_FALSE(cached);
    package::Span lb;
    ASSERT_EQ(local.blob(i, lb, err), core::Status::Ok);
    EXPECT_EQ(b, std::vector<uint8_t>(lb.data, lb.data + lb.size));
  }
  const uint64_t requests = r.stats().link.requests;
  std::vector<uint8_t> b;
  bool cached = false;
  ASSERT_EQ(r.blob(3, b, err, &cached), core::Status::Ok) << err;
  EXPECT_TRUE(cached);
  EXPECT_EQ(r.stats().link.requests, requests);
  // A restart: a new reader, the same cache on disk.
  remote::RemotePackage again;
  ASSERT_EQ(again.open(nginx_.url("/city.blvd"), opt_, err), core::Status::Ok) << err;
  EXPECT_EQ(again.identity(), r.identity());
  for (uint32_t i = 0; i < again.blobCount(); ++i) {
    ASSERT_EQ(again.blob(i, b, err, &cached), core::Status::Ok) << err;
    EXPECT_TRUE(cached) << "blob " << i;
  }
  EXPECT_EQ(again.stats().link.requests, 1u);  // the mirror is this package's: not fetched again
}

TEST_F(RemotePkg, APackageSwappedOnTheServerIsNoticedAndItsCacheRebuilt) {
  remote::RemotePackage r;
  std::string err;
  ASSERT_EQ(r.open(nginx_.url("/city.blvd"), opt_, err), core::Status::Ok) << err;
  std::vector<uint8_t> b;
  ASSERT_EQ(r.blob(0, b, err), core::Status::Ok) << err;
  writePackage(work_ + "/www/city.blvd", 7, 50);
  EXPECT_EQ(r.blob(1, b, err), core::Status::Corrupt);
  EXPECT_TRUE(r.changed());
  remote::RemotePackage fresh;
  ASSERT_EQ(fresh.open(nginx_.url("/city.blvd"), opt_, err), core::Status::Ok) << err;
  EXPECT_NE(fresh.identity(), r.identity());
  EXPECT_EQ(fresh.blobCount(), 7u);
  EXPECT_EQ(fresh.stats().cache_bytes, fresh.stats().mirror_bytes);  // the old package's blob went with its identity
  bool cached = true;
  ASSERT_EQ(fresh.blob(0, b, err, &cached), core::Status::Ok) << err;
  EXPECT_FALSE(cached);
  EXPECT_EQ(b, bytesOf(2000, 60));
}

TEST_F(RemotePkg, ACorruptBlobOnTheServerIsRefusedAndNotCached) {
  remote::RemotePackage r;
  std::string err;
  ASSERT_EQ(r.open(nginx_.url("/city.blvd"), opt_, err), core::Status::Ok) << err;
  const package::BlobInfo info = r.blobInfo(2);
  const auto mtime = fs::last_write_time(work_ + "/www/city.blvd");
  {
    std::fstream f(work_ + "/www/city.blvd", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(std::streamoff(info.offset + 10));
    f.put('\xAA');
  }
  fs::last_write_time(work_ + "/www/city.blvd", mtime);  // bad storage, same ETag: only the CRC can tell
  std::vector<uint8_t> b;
  EXPECT_EQ(r.blob(2, b, err), core::Status::Corrupt);
  EXPECT_NE(err.find("blob 2 at offset " + std::to_string(info.offset) + ": CRC mismatch"), std::string::npos) << err;
  EXPECT_FALSE(r.cached(2));
}

TEST_F(RemotePkg, WhatIsNotAPackageIsRefusedNamingTheUrl) {
  std::ofstream(work_ + "/www/notes.txt") << "not a package";
  remote::RemotePackage r;
  std::string err;
  EXPECT_EQ(r.open(nginx_.url("/notes.txt"), opt_, err), core::Status::Corrupt);
  EXPECT_NE(err.find("/notes.txt"), std::string::npos) << err;
  EXPECT_EQ(r.open(nginx_.url("/missing.blvd"), opt_, err), core::Status::NotFound);
}
