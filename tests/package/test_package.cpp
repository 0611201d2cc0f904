// Package container: round trip, every-byte corruption of header and
// directory, truncation at every boundary, foreign files, bad blobs, and
// structurally bad files with valid checksums.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <iterator>
#include <set>

#include "package/reader.h"
#include "package/writer.h"
#include "package_test_util.h"

namespace blvd::package {
namespace {

using core::Status;
using namespace testutil;

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

TEST(Crc32c, KnownVectors) {
  // RFC 3720 B.4 and the usual check value.
  EXPECT_EQ(crc32c("123456789", 9), 0xE3069283u);
  std::vector<uint8_t> zeros(32, 0), ones(32, 0xFF), inc(32);
  for (int i = 0; i < 32; ++i) inc[i] = static_cast<uint8_t>(i);
  EXPECT_EQ(crc32c(zeros.data(), 32), 0x8A9136AAu);
  EXPECT_EQ(crc32c(ones.data(), 32), 0x62A8AB43u);
  EXPECT_EQ(crc32c(inc.data(), 32), 0x46DD794Eu);
  // Chaining equals one pass, at every split (exercises the 8-byte path).
  const auto data = pattern(100, 9);
  for (size_t split = 0; split <= data.size(); ++split)
    EXPECT_EQ(crc32c(data.data() + split, data.size() - split, crc32c(data.data(), split)),
              crc32c(data.data(), data.size()));
}

// The CPU's CRC32 instruction (where there is one) and the tables agree on
// every length and alignment, and both pass the known vectors.
TEST(Crc32c, InstructionAndTablesAgree) {
  EXPECT_EQ(detail::crc32cTables("123456789", 9), 0xE3069283u);
#if defined(__x86_64__)
  EXPECT_TRUE(detail::crc32cAccelerated()) << "x86-64 CPUs since 2008 have SSE4.2";
#endif
  const auto data = pattern(300, 3);
  for (size_t off = 0; off < 9; ++off)
    for (size_t n = 0; off + n <= data.size(); n += 7)
      for (uint32_t seed : {0u, 0xDEADBEEFu})
        ASSERT_EQ(crc32c(data.data() + off, n, seed), detail::crc32cTables(data.data() + off, n, seed))
            << "offset " << off << " length " << n;
}

TEST(Format, TagsReadLeftToRight) {
  const uint32_t t = kSectionGraph;
  char c[4];
  std::memcpy(c, &t, 4);
  EXPECT_EQ(std::string(c, 4), "GRPH");
  EXPECT_EQ(tagToString(kSectionBlocks), "BLCK");
  EXPECT_EQ(tagToString(0x01020304), "0x01020304");
}

TEST(Package, RoundTrip) {
  TempDir dir;
  const std::string path = dir.file("monaco.blvd");
  PackageWriter w = sampleWriter();
  EXPECT_EQ(w.sectionBytes(kSectionGraph), 101u);
  EXPECT_EQ(w.sectionBytes(kSectionMeta), 0u);
  EXPECT_EQ(w.sectionBytes(kSectionBlobIndex), kBlobIndexPrefix + 5 * kBlobEntrySize);
  w.write(path);
  // Nothing left beside it: the package alone (its temporary file renamed over it).
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), std::filesystem::directory_iterator()), 1);
  EXPECT_EQ(std::filesystem::file_size(path), w.fileBytes());
  EXPECT_EQ(readFile(path), w.toBytes());

  PackageReader r;
  std::string err;
  ASSERT_EQ(PackageReader::open(path, r, err), Status::Ok) << err;
  EXPECT_TRUE(r.isOpen());
  EXPECT_EQ(r.fileSize(), w.fileBytes());
  EXPECT_EQ(r.name(), path);

  const PackageHeader& h = r.header();
  const PackageHeader e = sampleHeader();
  EXPECT_EQ(h.version_major, kVersionMajor);
  EXPECT_EQ(h.version_minor, kVersionMinor);
  EXPECT_EQ(h.origin_lat, e.origin_lat);
  EXPECT_EQ(h.origin_lon, e.origin_lon);
  EXPECT_EQ(h.origin_h, e.origin_h);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(h.bounds_min[i], e.bounds_min[i]);
    EXPECT_EQ(h.bounds_max[i], e.bounds_max[i]);
  }
  EXPECT_EQ(h.junction_count, e.junction_count);
  EXPECT_EQ(h.cell_count, e.cell_count);
  EXPECT_EQ(h.block_count, e.block_count);
  EXPECT_EQ(h.building_count, e.building_count);
  EXPECT_EQ(h.triangle_count, e.triangle_count);
  EXPECT_EQ(h.max_block_blob_bytes, e.max_block_blob_bytes);
  EXPECT_EQ(h.max_cell_blob_bytes, e.max_cell_blob_bytes);
  EXPECT_EQ(h.source_bytes, e.source_bytes);
  const auto got = poolSizing(h), want = poolSizing(e);
  ASSERT_EQ(got.size(), 23u);
  for (size_t i = 0; i < got.size(); ++i) EXPECT_EQ(got[i].value, want[i].value) << got[i].name;

  // Sections: contents, alignment, directory order (user sections, TPCR, BIDX, BDAT).
  const uint32_t tags[] = {kSectionGraph, kSectionCells, kSectionBlocks};
  const uint8_t seeds[] = {1, 2, 3};
  const size_t sizes[] = {101, 64, 37};
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(r.hasSection(tags[i]));
    Span s = r.section(tags[i]);
    EXPECT_EQ(s.offset % kAlignment, 0u);
    EXPECT_EQ(std::vector<uint8_t>(s.data, s.data + s.size), pattern(sizes[i], seeds[i]));
    Span c;
    EXPECT_EQ(r.checkedSection(tags[i], c, err), Status::Ok) << err;
    EXPECT_EQ(c.data, s.data);
  }
  ASSERT_EQ(r.sections().size(), 6u);
  EXPECT_EQ(r.sections()[3].tag, kSectionTablePages);
  EXPECT_EQ(r.sections()[4].tag, kSectionBlobIndex);
  EXPECT_EQ(r.sections()[5].tag, kSectionBlobData);
  ASSERT_NE(r.tablePages(), nullptr);
  ASSERT_EQ(r.tablePages()->runs.size(), 3u);  // one per section given, a page each
  for (int i = 0; i < 3; ++i) {
    const TablePageRun& run = r.tablePages()->runs[i];
    EXPECT_EQ(run.tag, tags[i]);
    EXPECT_EQ(run.pages, 1u);
    const std::vector<uint8_t> p = pattern(sizes[i], seeds[i]);
    EXPECT_EQ(tablePageCrc(r.section(kSectionTablePages).data, run, 0), crc32c(p.data(), p.size()));
  }
  EXPECT_FALSE(r.hasSection(kSectionMeta));
  EXPECT_TRUE(r.section(kSectionMeta).empty());
  EXPECT_EQ(r.section(kSectionMeta).data, nullptr);
  Span none;
  EXPECT_EQ(r.checkedSection(kSectionMeta, none, err), Status::NotFound);
  EXPECT_TRUE(contains(err, "META")) << err;

  ASSERT_EQ(r.blobCount(), 5u);
  for (uint32_t i = 0; i < 5; ++i) {
    Span b;
    ASSERT_EQ(r.blob(i, b, err), Status::Ok) << err;
    EXPECT_EQ(b.offset % kAlignment, 0u);
    EXPECT_EQ(b.offset, r.blobInfo(i).offset);
    EXPECT_EQ(std::vector<uint8_t>(b.data, b.data + b.size), pattern(50 + 13 * i, static_cast<uint8_t>(10 + i)));
    // Zero-copy: the span points into the mapping, at its file offset.
    EXPECT_EQ(b.data, r.section(kSectionBlobData).data + (b.offset - r.section(kSectionBlobData).offset));
  }
  Span b;
  EXPECT_EQ(r.blob(5, b, err), Status::NotFound);
  EXPECT_EQ(r.verify(err), Status::Ok) << err;

  // Move: the new owner works, the old one is closed.
  PackageReader moved = std::move(r);
  EXPECT_FALSE(r.isOpen());  // NOLINT(bugprone-use-after-move): moved-from state is specified
  EXPECT_EQ(moved.verify(err), Status::Ok) << err;
  EXPECT_EQ(r.verify(err), Status::Misuse);

  // The throwing convenience and the in-memory reader see the same package.
  PackageReader t = PackageReader::openOrThrow(path);
  EXPECT_EQ(t.blobCount(), 5u);
  const std::vector<uint8_t> bytes = readFile(path);
  PackageReader m;
  ASSERT_EQ(PackageReader::openMemory(bytes.data(), bytes.size(), "mem.blvd", m, err), Status::Ok) << err;
  EXPECT_EQ(m.verify(err), Status::Ok) << err;
  EXPECT_EQ(m.header().triangle_count, e.triangle_count);
}

TEST(Package, EmptyPackageAndOverwrite) {
  TempDir dir;
  const std::string path = dir.file("empty.blvd");
  PackageWriter w;
  w.write(path);
  PackageReader r;
  std::string err;
  ASSERT_EQ(PackageReader::open(path, r, err), Status::Ok) << err;
  EXPECT_EQ(r.blobCount(), 0u);
  EXPECT_EQ(r.verify(err), Status::Ok) << err;
  // Renaming over a mapped file leaves the mapping intact.
  sampleWriter().write(path);
  EXPECT_EQ(r.verify(err), Status::Ok) << err;
  PackageReader r2;
  ASSERT_EQ(PackageReader::open(path, r2, err), Status::Ok) << err;
  EXPECT_EQ(r2.blobCount(), 5u);
}

TEST(Package, WriterMisuse) {
  PackageWriter w;
  w.addSection(kSectionGraph, {1, 2, 3});
  try {
    w.addSection(kSectionGraph, {});
    FAIL() << "duplicate tag accepted";
  } catch (const core::Error& e) {
    EXPECT_EQ(e.status(), Status::InvalidArg);
    EXPECT_TRUE(contains(e.what(), "GRPH")) << e.what();
  }
  EXPECT_THROW(w.addSection(kSectionBlobIndex, {}), core::Error);
  EXPECT_THROW(w.addSection(kSectionBlobData, {}), core::Error);
}

TEST(Package, WriteFailureNamesPath) {
  TempDir dir;
  const std::string path = dir.file("no/such/dir/x.blvd");
  try {
    sampleWriter().write(path);
    FAIL() << "write into a missing directory succeeded";
  } catch (const core::Error& e) {
    EXPECT_EQ(e.status(), Status::Io);
    EXPECT_TRUE(contains(e.what(), path)) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp." + std::to_string(::getpid())));
}

TEST(Package, OpenFailures) {
  TempDir dir;
  PackageReader r;
  std::string err;
  EXPECT_EQ(PackageReader::open(dir.file("missing.blvd"), r, err), Status::Io);
  EXPECT_TRUE(contains(err, "missing.blvd")) << err;
  EXPECT_EQ(PackageReader::open(dir.path(), r, err), Status::Io);  // a directory
  EXPECT_TRUE(contains(err, dir.path())) << err;
  writeFile(dir.file("zero.blvd"), {});
  EXPECT_EQ(PackageReader::open(dir.file("zero.blvd"), r, err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "zero.blvd") && contains(err, "bad magic")) << err;
  EXPECT_FALSE(r.isOpen());
  try {
    PackageReader::openOrThrow(dir.file("zero.blvd"));
    FAIL();
  } catch (const core::Error& e) {
    EXPECT_EQ(e.status(), Status::Corrupt);
  }
  // Just the magic, nothing else.
  std::vector<uint8_t> magic(kMagic, kMagic + 8);
  writeFile(dir.file("magic.blvd"), magic);
  EXPECT_EQ(PackageReader::open(dir.file("magic.blvd"), r, err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "magic.blvd") && contains(err, "offset 0") && contains(err, "truncated")) << err;
}

TEST(Package, ForeignFiles) {
  TempDir dir;
  PackageReader r;
  std::string err;
  const std::string pbf = BLVD_DATA_DIR "/osm/monaco-geofabrik-2026.osm.pbf";
  ASSERT_TRUE(std::filesystem::exists(pbf));
  EXPECT_EQ(PackageReader::open(pbf, r, err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "monaco-geofabrik-2026.osm.pbf: not a blvd package (bad magic")) << err;
  const std::string glb = BLVD_TEST_DATA_DIR "/gltf/Box.glb";
  EXPECT_EQ(PackageReader::open(glb, r, err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "Box.glb") && contains(err, "bad magic")) << err;
  std::vector<uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  png.resize(4096, 0);
  writeFile(dir.file("image.png"), png);
  EXPECT_EQ(PackageReader::open(dir.file("image.png"), r, err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "image.png") && contains(err, "bad magic") && contains(err, "offset 0")) << err;
}

// Every single-byte change in the header or the directory must make open()
// fail with Corrupt, naming the file and an offset: the header CRC covers all
// of the header (reserved space included) and the directory CRC, which in turn
// covers the directory.
TEST(Package, EveryHeaderAndDirectoryByteFlipIsCaught) {
  TempDir dir;
  const std::vector<uint8_t> good = sampleWriter().toBytes();
  const size_t dir_end = kHeaderSize + 5 * kDirEntrySize;
  const std::string path = dir.file("flip.blvd");
  for (size_t i = 0; i < dir_end; ++i) {
    for (uint8_t mask : {uint8_t{0x01}, uint8_t{0x80}}) {
      std::vector<uint8_t> b = good;
      b[i] ^= mask;
      writeFile(path, b);
      PackageReader r;
      std::string err;
      const Status s = PackageReader::open(path, r, err);
      ASSERT_EQ(s, Status::Corrupt) << "byte " << i << " mask " << int(mask) << ": " << err;
      EXPECT_TRUE(contains(err, "flip.blvd")) << err;
      EXPECT_TRUE(contains(err, "offset ")) << err;
    }
  }
}

TEST(Package, TruncationAtEveryBoundary) {
  TempDir dir;
  const std::vector<uint8_t> good = sampleWriter().toBytes();
  PackageReader ref;
  std::string err;
  ASSERT_EQ(PackageReader::openMemory(good.data(), good.size(), "ref", ref, err), Status::Ok);
  std::set<size_t> cuts = {0, 1, 7, 8, 9, 23, 24, 100, kHeaderSize - 1, kHeaderSize, kHeaderSize + 1,
                           kHeaderSize + kDirEntrySize, good.size() - 1};
  for (const SectionInfo& s : ref.sections())
    for (uint64_t c : {s.offset, s.offset + 1, s.offset + s.size / 2, s.offset + s.size, s.offset + s.size - 1})
      if (c < good.size()) cuts.insert(c);
  for (uint32_t i = 0; i < ref.blobCount(); ++i) {
    const BlobInfo& b = ref.blobInfo(i);
    for (uint64_t c : {b.offset, b.offset + 3, b.offset + b.size - 1, b.offset + b.size})
      if (c < good.size()) cuts.insert(c);
  }
  const std::string path = dir.file("cut.blvd");
  for (size_t cut : cuts) {
    writeFile(path, std::vector<uint8_t>(good.begin(), good.begin() + static_cast<ptrdiff_t>(cut)));
    PackageReader r;
    const Status s = PackageReader::open(path, r, err);
    ASSERT_EQ(s, Status::Corrupt) << "cut at " << cut;
    EXPECT_TRUE(contains(err, "cut.blvd")) << err;
    EXPECT_TRUE(contains(err, "offset ")) << err;
    if (cut >= kHeaderSize) {
      EXPECT_TRUE(contains(err, "truncated")) << err;
    }
  }
  // Trailing garbage is refused too (the header records the size).
  std::vector<uint8_t> longer = good;
  longer.push_back(0);
  PackageReader r;
  EXPECT_EQ(PackageReader::openMemory(longer.data(), longer.size(), "long", r, err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "trailing")) << err;
}

TEST(Package, FlippedBlobByteIsReportedWithItsOffset) {
  TempDir dir;
  std::vector<uint8_t> b = sampleWriter().toBytes();
  PackageReader ref;
  std::string err;
  ASSERT_EQ(PackageReader::openMemory(b.data(), b.size(), "ref", ref, err), Status::Ok);
  const BlobInfo bad = ref.blobInfo(2);
  ref.close();
  b[bad.offset + 5] ^= 0x10;
  const std::string path = dir.file("blob.blvd");
  writeFile(path, b);
  PackageReader r;
  ASSERT_EQ(PackageReader::open(path, r, err), Status::Ok) << err;  // open does not read blobs
  Span s;
  EXPECT_EQ(r.blob(1, s, err), Status::Ok);
  EXPECT_EQ(r.blob(2, s, err), Status::Corrupt);
  EXPECT_TRUE(s.empty());
  const std::string where = "blob 2 at offset " + std::to_string(bad.offset);
  EXPECT_TRUE(contains(err, "blob.blvd") && contains(err, where) && contains(err, "checksum")) << err;
  EXPECT_EQ(r.verify(err), Status::Corrupt);
  // verify checks sections first: BDAT's own CRC covers the blob bytes too.
  EXPECT_TRUE(contains(err, "blob.blvd") && contains(err, "section BDAT")) << err;
}

TEST(Package, FlippedSectionAndPaddingBytes) {
  std::vector<uint8_t> good = sampleWriter().toBytes();
  PackageReader ref;
  std::string err;
  ASSERT_EQ(PackageReader::openMemory(good.data(), good.size(), "ref", ref, err), Status::Ok);
  const Span blocks = ref.section(kSectionBlocks);
  const uint64_t blocks_off = blocks.offset;
  const uint64_t pad = blocks.offset + blocks.size;  // 37 bytes: padding follows
  ref.close();

  std::vector<uint8_t> b = good;
  b[blocks_off + 3] ^= 1;
  PackageReader r;
  ASSERT_EQ(PackageReader::openMemory(b.data(), b.size(), "sec.blvd", r, err), Status::Ok);
  Span s;
  EXPECT_EQ(r.checkedSection(kSectionBlocks, s, err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "sec.blvd: section BLCK at offset " + std::to_string(blocks_off))) << err;
  EXPECT_EQ(r.verify(err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "section BLCK at offset " + std::to_string(blocks_off))) << err;

  b = good;
  ASSERT_NE(pad % kAlignment, 0u);
  b[pad] = 0x5A;
  ASSERT_EQ(PackageReader::openMemory(b.data(), b.size(), "pad.blvd", r, err), Status::Ok);
  EXPECT_EQ(r.verify(err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "pad.blvd: padding at offset " + std::to_string(pad))) << err;
}

// TPCR's own CRC right, one of its page CRCs wrong: verify() names the
// section, the page and its offset; a run whose page count does not fit its
// section is refused at open.
TEST(Package, TablePageCrcsAreCheckedByVerifyAndTheirShapeAtOpen) {
  std::vector<uint8_t> b = sampleWriter().toBytes();
  PackageReader r;
  std::string err;
  ASSERT_EQ(PackageReader::openMemory(b.data(), b.size(), "tp.blvd", r, err), Status::Ok) << err;
  const Span t = r.section(kSectionTablePages);
  const uint64_t cells_at = r.section(kSectionCells).offset;
  const TablePageRun cells = r.tablePages()->runs[1];
  r.close();
  const size_t entry = testutil::dirEntryOffset(b, kSectionTablePages);
  auto reseal = [&] {
    detail::put<uint32_t>(b.data() + entry + detail::dir::kCrc, crc32c(b.data() + t.offset, t.size));
    resealChecksums(b);
  };
  detail::put<uint32_t>(b.data() + t.offset + cells.crcs_at, 0xdeadbeefu);
  reseal();
  ASSERT_EQ(PackageReader::openMemory(b.data(), b.size(), "tp.blvd", r, err), Status::Ok) << err;
  EXPECT_EQ(r.verify(err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "tp.blvd: section CELL page 0 at offset " + std::to_string(cells_at))) << err;
  r.close();
  detail::put<uint32_t>(b.data() + t.offset + 12 + 8 + 4, 2);  // CELL's run: 2 pages for 64 bytes
  reseal();
  EXPECT_EQ(PackageReader::openMemory(b.data(), b.size(), "tp.blvd", r, err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "table page CRCs TPCR at offset")) << err;
  EXPECT_TRUE(contains(err, "section CELL of 64 bytes has 1 pages, not 2")) << err;
}

// Files whose checksums are right but whose structure is not: what a buggy
// writer (or a fuzzer that fixes CRCs) produces.
class Resealed : public ::testing::Test {
 protected:
  void SetUp() override { bytes = sampleWriter().toBytes(); }
  Status open(std::string& err) {
    resealChecksums(bytes);
    PackageReader r;
    return PackageReader::openMemory(bytes.data(), bytes.size(), "monaco.blvd", r, err);
  }
  template <typename T>
  void set(size_t off, T v) { detail::put<T>(bytes.data() + off, v); }
  template <typename T>
  T get(size_t off) { return detail::get<T>(bytes.data() + off); }
  std::vector<uint8_t> bytes;
};

TEST_F(Resealed, SectionPastEndOfFile) {
  const size_t e = dirEntryOffset(bytes, kSectionBlocks);
  const uint64_t off = get<uint64_t>(e + detail::dir::kOffset);
  set<uint64_t>(e + detail::dir::kSize, 9999);
  std::string err;
  EXPECT_EQ(open(err), Status::Corrupt);
  EXPECT_EQ(err, "monaco.blvd: section BLCK at offset " + std::to_string(off) +
                     ": length 9999 runs past end of file (" + std::to_string(bytes.size()) + " bytes)");
}

TEST_F(Resealed, HugeLengthDoesNotWrap) {
  const size_t e = dirEntryOffset(bytes, kSectionGraph);
  set<uint64_t>(e + detail::dir::kSize, ~uint64_t{0} - 100);
  std::string err;
  EXPECT_EQ(open(err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "section GRPH") && contains(err, "runs past end of file")) << err;
}

TEST_F(Resealed, MisalignedSection) {
  const size_t e = dirEntryOffset(bytes, kSectionCells);
  set<uint64_t>(e + detail::dir::kOffset, get<uint64_t>(e + detail::dir::kOffset) + 4);
  std::string err;
  EXPECT_EQ(open(err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "section CELL at offset") && contains(err, "aligned")) << err;
}

TEST_F(Resealed, OverlappingSections) {
  const size_t g = dirEntryOffset(bytes, kSectionGraph);
  const size_t c = dirEntryOffset(bytes, kSectionCells);
  set<uint64_t>(c + detail::dir::kOffset, get<uint64_t>(g + detail::dir::kOffset) + 8);
  std::string err;
  EXPECT_EQ(open(err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "overlaps section")) << err;
}

TEST_F(Resealed, SectionOverDirectory) {
  const size_t g = dirEntryOffset(bytes, kSectionGraph);
  set<uint64_t>(g + detail::dir::kOffset, kHeaderSize + 8);
  std::string err;
  EXPECT_EQ(open(err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "section GRPH at offset 264: overlaps the directory")) << err;
}

TEST_F(Resealed, DuplicateTag) {
  const size_t c = dirEntryOffset(bytes, kSectionCells);
  set<uint32_t>(c + detail::dir::kTag, kSectionGraph);
  std::string err;
  EXPECT_EQ(open(err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "section GRPH") && contains(err, "twice")) << err;
}

TEST_F(Resealed, BlobOutsideBlobData) {
  const size_t bidx = dirEntryOffset(bytes, kSectionBlobIndex);
  const uint64_t index_off = get<uint64_t>(bidx + detail::dir::kOffset);
  const size_t entry = index_off + kBlobIndexPrefix + 4 * kBlobEntrySize;
  const uint64_t blob_off = get<uint64_t>(entry + detail::blob::kOffset);
  set<uint64_t>(entry + detail::blob::kSize, 4096);
  // The BIDX section CRC is not checked at open (verify does): only the
  // blob's bounds fail here.
  std::string err;
  EXPECT_EQ(open(err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "monaco.blvd: blob 4 at offset " + std::to_string(blob_off) +
                                ": length 4096 lies outside section BDAT"))
      << err;
}

TEST_F(Resealed, BlobIndexCountMismatch) {
  const size_t bidx = dirEntryOffset(bytes, kSectionBlobIndex);
  const uint64_t index_off = get<uint64_t>(bidx + detail::dir::kOffset);
  set<uint32_t>(index_off, 1000000);
  std::string err;
  EXPECT_EQ(open(err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "section BIDX at offset " + std::to_string(index_off))) << err;
}

TEST_F(Resealed, FileSizeField) {
  set<uint64_t>(detail::hdr::kFileSize, bytes.size() + 8);
  std::string err;
  EXPECT_EQ(open(err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "header at offset 24") && contains(err, "truncated")) << err;
}

TEST_F(Resealed, HeaderSizeField) {
  set<uint32_t>(detail::hdr::kHeaderSize, 100);
  std::string err;
  EXPECT_EQ(open(err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "header at offset 12: header size 100 is invalid")) << err;
}

TEST_F(Resealed, NewerMajorVersionIsUnsupported) {
  set<uint16_t>(detail::hdr::kVersionMajor, kVersionMajor + 1);
  std::string err;
  EXPECT_EQ(open(err), Status::Unsupported);
  const std::string v = std::to_string(kVersionMajor);
  const std::string minor = "." + std::to_string(kVersionMinor);  // the file keeps its minor
  EXPECT_TRUE(contains(err, "version " + std::to_string(kVersionMajor + 1) + minor) && contains(err, v + ".x")) << err;
}

// An older major package (2.x: IMPO layers without their run; 1.x: BLCK
// without levels of detail) is refused as a whole, not misread.
TEST_F(Resealed, OlderMajorVersionIsUnsupported) {
  for (uint16_t major : {uint16_t(kVersionMajor - 1), uint16_t(1)}) {
    set<uint16_t>(detail::hdr::kVersionMajor, major);
    set<uint16_t>(detail::hdr::kVersionMinor, 0);
    std::string err;
    EXPECT_EQ(open(err), Status::Unsupported);
    EXPECT_TRUE(contains(err, "version " + std::to_string(major) + ".0") &&
                contains(err, "this build reads " + std::to_string(kVersionMajor) + ".x"))
        << err;
  }
}

TEST_F(Resealed, NewerMinorVersionOpens) {
  set<uint16_t>(detail::hdr::kVersionMinor, 7);
  std::string err;
  EXPECT_EQ(open(err), Status::Ok) << err;
}

TEST_F(Resealed, NonsenseOrigin) {
  set<double>(detail::hdr::kOriginLat, 123.0);
  std::string err;
  EXPECT_EQ(open(err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "origin")) << err;
}

TEST_F(Resealed, DirectoryPastEnd) {
  set<uint32_t>(detail::hdr::kDirCount, 0x10000000);
  std::string err;
  EXPECT_EQ(open(err), Status::Corrupt);
  EXPECT_TRUE(contains(err, "directory at offset 256")) << err;
}

}  // namespace
}  // namespace blvd::package
