// Blobs stored as zstd frames (package format 4.0), with the built-in
// dictionary where that is smaller (6.0): the round trip through the writer
// and both read paths, the choice to store a blob as is when compressing does
// not pay, and a damaged frame or a BIDX entry that lies about it, each named
// with the blob and its offset.
#include <gtest/gtest.h>

#include <random>

#include "package/blob_codec.h"
#include "package/reader.h"
#include "package/writer.h"
#include "package_test_util.h"

namespace blvd::package {
namespace {

using core::Status;
using namespace testutil;

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

std::vector<uint8_t> noise(size_t n) {
  std::mt19937 rng(7);
  std::vector<uint8_t> v(n);
  for (uint8_t& b : v) b = static_cast<uint8_t>(rng());
  return v;
}

// Blob 0 compresses (a repeating pattern, like a GLB's JSON), blob 1 does
// not (noise, like a WebP atlas), blob 2 is empty.
std::vector<std::vector<uint8_t>> contents() { return {pattern(5000, 3), noise(3000), {}}; }

// glTF JSON as an impostor layer's GLB starts, numbers of its own: what the
// dictionary is made of, not a copy of it.
std::vector<uint8_t> layerJson() {
  const std::string j =
      R"({"accessors":[{"componentType":5123,"count":612,"type":"SCALAR"},{"componentType":5126,"count":287,)"
      R"("max":[-211.5,9.75,40.25],"min":[-480.125,-1.5,-302.0],"type":"VEC3"},{"componentType":5121,"count":287,)"
      R"("type":"SCALAR"}],"asset":{"generator":"blvd","version":"2.0"},"bufferViews":[{"buffer":0,"byteLength":1204,)"
      R"("byteOffset":0},{"buffer":0,"byteLength":128,"byteOffset":1204},{"buffer":0,"byteLength":1876,)"
      R"("byteOffset":1332}],"buffers":[{"byteLength":3208}],"extensionsRequired":["KHR_draco_mesh_compression",)"
      R"("BLVD_projected_texcoords","EXT_texture_webp"],"extensionsUsed":["KHR_draco_mesh_compression",)"
      R"("BLVD_projected_texcoords","EXT_texture_webp","KHR_materials_unlit"],"images":[{"bufferView":2,)"
      R"("mimeType":"image/webp"}],"materials":[{"doubleSided":false,"extensions":{"KHR_materials_unlit":{}},)"
      R"("pbrMetallicRoughness":{"baseColorFactor":[1.0,1.0,1.0,1.0],"baseColorTexture":{"index":0},)"
      R"("metallicFactor":0.0,"roughnessFactor":1.0}}]})";
  return std::vector<uint8_t>(j.begin(), j.end());
}

std::vector<uint8_t> packageOf(const std::vector<std::vector<uint8_t>>& blobs, int level) {
  PackageWriter w;
  w.setHeader(sampleHeader());
  w.addSection(kSectionGraph, pattern(40, 1));
  w.setBlobCompression(level);
  for (const auto& b : blobs) w.addBlob(b);
  return w.toBytes();
}

TEST(BlobCodec, PackUsesAFrameOnlyWhereItIsSmaller) {
  const StoredBlob a = packBlob(pattern(5000, 3), 19);
  EXPECT_EQ(a.flags, kBlobZstd);
  EXPECT_EQ(a.contents_size, 5000u);
  EXPECT_LT(a.bytes.size(), 1000u);
  const StoredBlob b = packBlob(noise(3000), 19);
  EXPECT_EQ(b.flags, 0u);
  EXPECT_EQ(b.bytes, noise(3000));
  const StoredBlob c = packBlob(pattern(5000, 3), 0);
  EXPECT_EQ(c.flags, 0u);
  EXPECT_EQ(c.bytes, pattern(5000, 3));
  EXPECT_THROW(packBlob({}, 23), core::Error);
  EXPECT_THROW(packBlob({}, -1), core::Error);
}

TEST(BlobCodec, GltfJsonTakesTheDictionary) {
  const StoredBlob a = packBlob(layerJson(), 19);
  EXPECT_EQ(a.flags, kBlobZstd | kBlobZstdDict);
  // Most of it is the dictionary's text: a fraction of a plain frame.
  EXPECT_LT(a.bytes.size(), layerJson().size() / 4) << a.bytes.size();
  PackageWriter w;
  w.setBlobCompression(19);
  w.addBlob(layerJson());
  EXPECT_EQ(w.blobContents(0), layerJson());
}

TEST(BlobCodec, RoundTripThroughTheMappingAndThroughPread) {
  const auto want = contents();
  const std::vector<uint8_t> bytes = packageOf(want, 19);
  TempDir dir;
  writeFile(dir.file("z.blvd"), bytes);
  for (const auto access : {PackageReader::Access::Map, PackageReader::Access::Read}) {
    PackageReader r;
    std::string err;
    ASSERT_EQ(PackageReader::open(dir.file("z.blvd"), r, err, access), Status::Ok) << err;
    EXPECT_EQ(r.header().max_blob_contents_bytes, 5000u);
    ASSERT_EQ(r.blobCount(), 3u);
    EXPECT_EQ(r.blobInfo(0).flags, kBlobZstd);
    EXPECT_EQ(r.blobInfo(0).contents_size, 5000u);
    EXPECT_LT(r.blobInfo(0).size, 1000u);
    EXPECT_EQ(r.blobInfo(1).flags, 0u);
    EXPECT_EQ(r.blobInfo(1).size, 3000u);
    std::vector<uint8_t> into;
    for (uint32_t i = 0; i < 3; ++i) {
      Span s;
      const Status st = access == PackageReader::Access::Map ? r.blobContents(i, into, s, err)
                                                             : r.readBlobContents(i, into, s, err);
      ASSERT_EQ(st, Status::Ok) << err;
      EXPECT_EQ(std::vector<uint8_t>(s.data, s.data + s.size), want[i]) << "blob " << i;
      EXPECT_EQ(s.offset, r.blobInfo(i).offset);
    }
    EXPECT_EQ(r.verify(err), access == PackageReader::Access::Map ? Status::Ok : Status::Misuse) << err;
  }
  // The writer gives the contents back too (the tiled bake translates them).
  PackageWriter w;
  w.setBlobCompression(19);
  w.addBlob(want[0]);
  EXPECT_EQ(w.blobContents(0), want[0]);
  EXPECT_LT(w.blob(0).size(), want[0].size());
}

TEST(BlobCodec, StoredBlobsCopyAsTheyAre) {
  PackageWriter w;
  w.addStoredBlob(packBlob(pattern(5000, 3), 19));
  EXPECT_EQ(w.blobContents(0), pattern(5000, 3));
  StoredBlob lie = packBlob(pattern(5000, 3), 19);
  lie.flags = 0;  // a frame said to be the contents themselves
  EXPECT_THROW(w.addStoredBlob(lie), core::Error);
  lie.flags = 4;
  EXPECT_THROW(w.addStoredBlob(lie), core::Error);
  lie.flags = kBlobZstdDict;  // the dictionary without a frame
  EXPECT_THROW(w.addStoredBlob(lie), core::Error);
}

// Files whose checksums are right but whose BIDX or frame is not.
class ResealedBlobs : public ::testing::Test {
 protected:
  virtual std::vector<std::vector<uint8_t>> blobs() const { return contents(); }
  void SetUp() override {
    bytes = packageOf(blobs(), 19);
    PackageReader r;
    std::string err;
    ASSERT_EQ(PackageReader::openMemory(bytes.data(), bytes.size(), "z.blvd", r, err), Status::Ok) << err;
    info = r.blobInfo(0);
    const size_t bidx = dirEntryOffset(bytes, kSectionBlobIndex);
    entry = detail::get<uint64_t>(bytes.data() + bidx + detail::dir::kOffset) + kBlobIndexPrefix;
  }
  // The blob's CRC, BIDX's and BDAT's in the directory, then the header's.
  Status reopen(PackageReader& r, std::string& err) {
    detail::put<uint32_t>(bytes.data() + entry + detail::blob::kCrc, crc32c(bytes.data() + info.offset, info.size));
    for (const uint32_t tag : {kSectionBlobIndex, kSectionBlobData}) {
      const size_t e = dirEntryOffset(bytes, tag);
      const uint64_t off = detail::get<uint64_t>(bytes.data() + e + detail::dir::kOffset);
      const uint64_t size = detail::get<uint64_t>(bytes.data() + e + detail::dir::kSize);
      detail::put<uint32_t>(bytes.data() + e + detail::dir::kCrc, crc32c(bytes.data() + off, size));
    }
    resealChecksums(bytes);
    return PackageReader::openMemory(bytes.data(), bytes.size(), "z.blvd", r, err);
  }
  Status contentsOf(std::string& err) {
    PackageReader r;
    Status st = reopen(r, err);
    if (st != Status::Ok) return st;
    std::vector<uint8_t> into;
    Span s;
    return r.blobContents(0, into, s, err);
  }
  std::vector<uint8_t> bytes;
  BlobInfo info;
  size_t entry = 0;
};

// The stored CRC catches damage on disk or on the link; this is a frame that
// a faulty writer sealed (its magic number is wrong).
TEST_F(ResealedBlobs, DamagedFrameIsCorrupt) {
  bytes[info.offset] ^= 0x5a;
  std::string err;
  EXPECT_EQ(contentsOf(err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "z.blvd: blob 0 at offset " + std::to_string(info.offset) + ": zstd frame")) << err;
}

TEST_F(ResealedBlobs, FrameShorterThanBidxSays) {
  detail::put<uint64_t>(bytes.data() + entry + detail::blob::kContents, 4000);
  std::string err;
  EXPECT_EQ(contentsOf(err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "blob 0 at offset " + std::to_string(info.offset))) << err;
}

TEST_F(ResealedBlobs, UnknownFlagIsRefusedAtOpen) {
  for (const uint32_t flags : {4u, 5u, kBlobZstdDict}) {
    detail::put<uint32_t>(bytes.data() + entry + detail::blob::kFlags, flags);
    PackageReader r;
    std::string err;
    EXPECT_EQ(reopen(r, err), Status::Corrupt);
    EXPECT_TRUE(contains(err, "blob 0 at offset " + std::to_string(info.offset) + ": unknown flags " +
                                  std::to_string(flags)))
        << err;
  }
}

// Blob 0 a frame made with the dictionary.
class ResealedDictionaryBlob : public ResealedBlobs {
 protected:
  std::vector<std::vector<uint8_t>> blobs() const override { return {layerJson()}; }
};

TEST_F(ResealedDictionaryBlob, ReadsBackAndNeedsItsFlag) {
  EXPECT_EQ(info.flags, kBlobZstd | kBlobZstdDict);
  std::string err;
  EXPECT_EQ(contentsOf(err), Status::Ok) << err;
  // Without the dictionary the frame names one zstd cannot find.
  detail::put<uint32_t>(bytes.data() + entry + detail::blob::kFlags, kBlobZstd);
  EXPECT_EQ(contentsOf(err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "z.blvd: blob 0 at offset " + std::to_string(info.offset) + ": zstd frame")) << err;
}

TEST_F(ResealedBlobs, FrameSaidToBeItsContents) {
  detail::put<uint32_t>(bytes.data() + entry + detail::blob::kFlags, 0);
  PackageReader r;
  std::string err;
  EXPECT_EQ(reopen(r, err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "stored as is, but its contents are 5000 bytes")) << err;
}

TEST_F(ResealedBlobs, ContentsOverTheHeadersLargest) {
  detail::put<uint64_t>(bytes.data() + entry + detail::blob::kContents, uint64_t{1} << 40);
  PackageReader r;
  std::string err;
  EXPECT_EQ(reopen(r, err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "more than the header's largest, 5000")) << err;
  detail::put<uint32_t>(bytes.data() + detail::hdr::kMaxBlobContents, 0xffffffffu);
  EXPECT_EQ(reopen(r, err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "header at offset 212")) << err;
}

}  // namespace
}  // namespace blvd::package
