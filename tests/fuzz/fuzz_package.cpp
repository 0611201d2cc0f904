// Fuzz target for the package reader: the input is opened from memory, from
// a file (the mmap path), and once more with all its checksums recomputed, so
// that mutations get past the CRCs to the structure checks and, through the
// blobs, to the GLB decoder; then as the runtime opens it (City, its tables
// paged) with each cell's tables read and the first cells' block levels and
// impostor layers decoded as the loader does. Every path must end in Ok or an
// error with a message; never a crash.
//
// Seeds: set BLVD_FUZZ_SEED_DIR and the target writes a small package there.
#include <fcntl.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "graph/segment_grid.h"
#include "package/format_detail.h"
#include "package/glb.h"
#include "package/reader.h"
#include "package/writer.h"
#include "stream/city.h"
#include "stream/paged_graph.h"
#include "seed_package.h"

namespace {

using namespace blvd::package;
using blvd::core::Status;

void check(Status s, const std::string& err) {
  if (s != Status::Ok && err.empty()) std::abort();  // every failure must say why
}

void exercise(const PackageReader& r) {
  std::string err;
  (void)r.header();
  for (const SectionInfo& si : r.sections()) {
    Span s = r.section(si.tag);
    if (s.size != si.size) std::abort();
    check(r.checkedSection(si.tag, s, err), err);
  }
  for (uint32_t i = 0; i < r.blobCount(); ++i) {
    Span b;
    const Status s = r.blob(i, b, err);
    check(s, err);
    if (s == Status::Ok) {
      std::vector<uint8_t> contents;
      Span glb;
      const Status u = r.blobContents(i, contents, glb, err);
      check(u, err);
      blvd::geo::MeshData m;
      if (u == Status::Ok) check(decodeGlb(glb.data, glb.size, m, err), err);
    }
  }
  Span none;
  if (r.blob(r.blobCount(), none, err) == Status::Ok) std::abort();
  check(r.verify(err), err);
}

// Recomputes every checksum it can reach: blob CRCs in BIDX, section CRCs in
// the directory, the directory CRC and the header CRC.
void reseal(std::vector<uint8_t>& b) {
  using detail::get;
  using detail::put;
  namespace h = detail::hdr;
  if (b.size() < kHeaderSize) return;
  const uint32_t header_size = get<uint32_t>(b.data() + h::kHeaderSize);
  if (header_size < h::kCrc + 4 || header_size > b.size()) return;
  auto sealHeader = [&] {
    const uint64_t dir_off = get<uint64_t>(b.data() + h::kDirOffset);
    const uint64_t dir_bytes = uint64_t{get<uint32_t>(b.data() + h::kDirCount)} * kDirEntrySize;
    if (dir_off <= b.size() && dir_bytes <= b.size() - dir_off)
      put<uint32_t>(b.data() + h::kDirCrc, crc32c(b.data() + dir_off, dir_bytes));
    put<uint32_t>(b.data() + h::kCrc, detail::headerCrc(b.data(), header_size));
  };
  sealHeader();
  PackageReader r;
  std::string err;
  if (PackageReader::openMemory(b.data(), b.size(), "reseal", r, err) != Status::Ok) return;
  const std::vector<SectionInfo> sections = r.sections();
  std::vector<BlobInfo> blobs;
  for (uint32_t i = 0; i < r.blobCount(); ++i) blobs.push_back(r.blobInfo(i));
  r.close();
  const uint64_t dir_off = get<uint64_t>(b.data() + h::kDirOffset);
  for (size_t j = 0; j < sections.size(); ++j) {
    if (sections[j].tag != kSectionBlobIndex) continue;
    const uint32_t entry_size = get<uint32_t>(b.data() + sections[j].offset + 4);
    for (size_t i = 0; i < blobs.size(); ++i)
      put<uint32_t>(b.data() + sections[j].offset + kBlobIndexPrefix + i * entry_size + detail::blob::kCrc,
                    crc32c(b.data() + blobs[i].offset, blobs[i].size));
  }
  for (size_t j = 0; j < sections.size(); ++j)
    put<uint32_t>(b.data() + dir_off + j * kDirEntrySize + detail::dir::kCrc,
                  crc32c(b.data() + sections[j].offset, sections[j].size));
  sealHeader();
}

// One scratch file per process, reused by every run. A plain char array (no
// destructor) so the atexit cleanup can still read it at exit.
const char* tempPath() {
  static char path[4096] = {};
  if (!path[0]) {
    const std::string tmpl = (std::filesystem::temp_directory_path() / "blvd_fuzz_pkg_XXXXXX").string();
    if (tmpl.size() >= sizeof path) std::abort();
    std::memcpy(path, tmpl.c_str(), tmpl.size() + 1);
    const int fd = ::mkstemp(path);
    if (fd < 0) std::abort();
    ::close(fd);
    std::atexit([] { ::unlink(path); });
  }
  return path;
}

// Decodes a cell's block levels and impostor layers as the loader does (read
// with pread, CRC-checked, then decoded): Ok, or an error that says why. Each
// blob once (`seen`), at most `budget` blobs an input.
void decodeCell(const blvd::stream::City& city, uint32_t c, const std::vector<blvd::stream::LayerInfo>& layers,
                uint32_t n_layers, std::vector<bool>& seen, int& budget) {
  std::string err;
  blvd::geo::MeshData m;
  for (uint32_t b : city.streets().localBlocks(c)) {
    const uint32_t blob_id = city.block(b).blob;
    if (blob_id >= seen.size() || seen[blob_id] || budget-- <= 0) continue;
    seen[blob_id] = true;
    blvd::stream::City::BlockBlob blob;
    const Status s = city.openBlock(b, blob, err);
    check(s, err);
    for (uint32_t k = 0; s == Status::Ok && k < city.block(b).lod_count; ++k) check(city.decodeBlockLevel(blob, k, m, err), err);
  }
  for (uint32_t i = 0; i < n_layers; ++i) {
    if (layers[i].blob >= seen.size() || seen[layers[i].blob] || budget-- <= 0) continue;
    seen[layers[i].blob] = true;
    check(city.decodeImpostorBlob(layers[i].blob, m, err), err);
  }
}

// Reads each cell's tables as the runtime would (checked at open: never a
// crash) and decodes the first cells' blobs.
void readEveryCell(const blvd::stream::City& city) {
  std::vector<blvd::stream::LayerInfo> layers(city.maxCellLayers());
  int budget = 16;
  std::vector<bool> seen(city.package().blobCount());
  for (uint32_t c = 0; c < city.streets().cellCount(); ++c) {
    uint32_t layered = 0, single = 0;
    city.cellLayers(c, layers.data(), static_cast<uint32_t>(layers.size()), &layered, &single);
    for (uint32_t b : city.streets().localBlocks(c)) (void)city.coverage(c, b), (void)city.block(b);
    for (uint32_t s : city.streets().successors(c)) (void)city.streets().halfedge(s);
    decodeCell(city, c, layers, layered + single, seen, budget);
  }
  // Each terrain tile's record and heights (records checked at open).
  if (const blvd::stream::TerrainPages* t = city.terrain()) {
    std::vector<float> h(size_t(t->layout().grid) * t->layout().grid);
    std::vector<uint8_t> hold;
    std::string err;
    for (uint32_t i = 0; i < t->layout().tiles() && i < 4096; ++i) check(city.terrainHeights(t->record(i), hold, h.data(), err), err);
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  const char* dir = std::getenv("BLVD_FUZZ_SEED_DIR");
  if (!dir || !*dir) return 0;
  std::filesystem::create_directories(dir);
  const blvd::geo::MeshData m = blvd_test::seedQuad();
  PackageWriter w;
  w.setHeader(blvd_test::seedHeader());
  w.addSection(kSectionMeta, {'{', '}'});
  w.addSection(kSectionBlocks, {1, 2, 3, 4, 5});
  w.addBlob(encodeGlb(m));
  GlbOptions plain;
  plain.codec = blvd::package::GlbCodec::Plain;
  w.setBlobCompression(19);  // a zstd frame, as the bake stores blobs
  w.addBlob(encodeGlb(m, plain));
  w.write((std::filesystem::path(dir) / "seed.blvd").string());
  blvd_test::writeGridPackage((std::filesystem::path(dir) / "graph.blvd").string());
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string err;
  {
    PackageReader r;
    const Status s = PackageReader::openMemory(data, size, "fuzz.blvd", r, err);
    check(s, err);
    if (s == Status::Ok) exercise(r);
  }
  {
    const char* path = tempPath();
    const int fd = ::open(path, O_WRONLY | O_TRUNC);
    if (fd < 0) std::abort();
    size_t done = 0;
    while (done < size) {
      const ssize_t w = ::write(fd, data + done, size - done);
      if (w <= 0) std::abort();
      done += static_cast<size_t>(w);
    }
    ::close(fd);
    PackageReader r;
    const Status s = PackageReader::open(path, r, err);
    check(s, err);
    if (s == Status::Ok) exercise(r);
  }
  {
    std::vector<uint8_t> copy(data, data + size);
    reseal(copy);
    PackageReader r;
    const Status s = PackageReader::openMemory(copy.data(), copy.size(), "resealed.blvd", r, err);
    check(s, err);
    if (s == Status::Ok) exercise(r);
    if (s == Status::Ok) {  // the tables as the runtime pages them, past the section CRCs
      const char* path = tempPath();
      std::FILE* f = std::fopen(path, "wb");
      if (!f || std::fwrite(copy.data(), 1, copy.size(), f) != copy.size()) std::abort();
      std::fclose(f);
      blvd::stream::City city;
      err.clear();
      const Status cs = city.open(path, err, blvd::stream::City::Tables::All, blvd::stream::City::GraphTables::Paged,
                                  {8, 256});
      check(cs, err);
      if (cs == Status::Ok) readEveryCell(city);
    }
  }
  return 0;
}
