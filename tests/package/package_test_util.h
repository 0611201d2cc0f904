// Helpers shared by the package tests: a scratch directory, file I/O, a small
// sample package, and re-sealing checksums so a test can build a structurally
// bad file that still passes the CRC checks.
#pragma once
#include <gtest/gtest.h>
#include <stdlib.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "package/format.h"
#include "package/format_detail.h"
#include "package/writer.h"

namespace blvd::package::testutil {

// A fresh directory under $TMPDIR, removed when the object goes away.
class TempDir {
 public:
  TempDir() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "blvd_pkg_XXXXXX").string();
    if (!::mkdtemp(tmpl.data())) throw std::runtime_error("mkdtemp failed");
    path_ = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  std::string file(const std::string& name) const { return path_ + "/" + name; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

inline void writeFile(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  ASSERT_TRUE(f.good()) << path;
}

inline std::vector<uint8_t> readFile(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

inline std::vector<uint8_t> pattern(size_t n, uint8_t seed) {
  std::vector<uint8_t> v(n);
  for (size_t i = 0; i < n; ++i) v[i] = static_cast<uint8_t>(seed + i * 7 + (i >> 3));
  return v;
}

inline PackageHeader sampleHeader() {
  PackageHeader h;
  h.origin_lat = 43.7384;
  h.origin_lon = 7.4246;
  h.origin_h = 55.5;
  h.bounds_min[0] = -1500.25f;
  h.bounds_min[1] = -900.5f;
  h.bounds_max[0] = 1600.75f;
  h.bounds_max[1] = 1100.0f;
  h.junction_count = 1234;
  h.cell_count = 321;
  h.block_count = 456;
  h.building_count = 1625;
  h.triangle_count = 9876543210ull;
  h.max_block_blob_bytes = 65536;
  h.max_cell_blob_bytes = 262144;
  h.source_bytes = 673936;
  // Pool sizing: distinct values, some past 32 bits where the field is 64.
  h.max_block_lod0_vertices = 1000;
  h.max_block_lod0_triangles = 1037;
  h.max_block_vertices = 1074;
  h.max_block_triangles = 1111;
  h.max_cell_local_blocks = 1148;
  h.max_cell_local_lod0_vertices = 1185;
  h.max_cell_local_lod0_triangles = 1222;
  h.max_cell_local_vertices = 1259;
  h.max_cell_local_triangles = 1296;
  h.max_cell_impostor_layers = 1333;
  h.max_cell_local_blob_bytes = 8589934602ull;
  h.max_cell_impostor_blob_bytes = 8589934603ull;
  h.max_cell_impostor_texture_bytes = 8589934604ull;
  h.max_cell_impostor_vertices = 1481;
  h.max_cell_impostor_triangles = 1518;
  h.max_impostor_texture_bytes = 1555;
  h.max_impostor_texture_width = 516;
  h.max_impostor_texture_height = 517;
  h.impostor_atlas_width = 560;
  h.impostor_atlas_height = 568;
  h.impostor_atlas_etc2_height = 608;
  return h;
}

// 3 sections and 5 blobs with sizes that leave padding between them.
inline PackageWriter sampleWriter() {
  PackageWriter w;
  w.setHeader(sampleHeader());
  w.addSection(kSectionGraph, pattern(101, 1));
  w.addSection(kSectionCells, pattern(64, 2));
  w.addSection(kSectionBlocks, pattern(37, 3));
  for (int i = 0; i < 5; ++i) w.addBlob(pattern(static_cast<size_t>(50 + 13 * i), static_cast<uint8_t>(10 + i)));
  return w;
}

// Recomputes the directory CRC (into the header) and then the header CRC.
inline void resealChecksums(std::vector<uint8_t>& b) {
  using detail::get;
  using detail::put;
  namespace h = detail::hdr;
  const uint64_t dir_off = get<uint64_t>(b.data() + h::kDirOffset);
  const uint32_t dir_count = get<uint32_t>(b.data() + h::kDirCount);
  const uint64_t dir_bytes = uint64_t{dir_count} * kDirEntrySize;
  if (dir_off <= b.size() && dir_bytes <= b.size() - dir_off)  // a test may have broken these on purpose
    put<uint32_t>(b.data() + h::kDirCrc, crc32c(b.data() + dir_off, dir_bytes));
  const uint32_t header_size = get<uint32_t>(b.data() + h::kHeaderSize);
  put<uint32_t>(b.data() + h::kCrc, detail::headerCrc(b.data(), header_size));
}

// Byte offset of the directory entry for `tag` in a package made by PackageWriter.
inline size_t dirEntryOffset(const std::vector<uint8_t>& b, uint32_t tag) {
  using detail::get;
  const uint32_t n = get<uint32_t>(b.data() + detail::hdr::kDirCount);
  for (uint32_t i = 0; i < n; ++i) {
    const size_t e = kHeaderSize + i * kDirEntrySize;
    if (get<uint32_t>(b.data() + e) == tag) return e;
  }
  ADD_FAILURE() << "no directory entry for " << tagToString(tag);
  return 0;
}

}  // namespace blvd::package::testutil
