#include "package/format.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

#include "package/format_detail.h"

#if defined(__x86_64__)
#include <nmmintrin.h>
#endif

namespace blvd::package {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "the package format is little-endian; big-endian hosts need byte swaps here");

namespace {

// Slice-by-8 tables, built once at compile time: table[0] is the classic
// byte-at-a-time table, table[k] advances a byte that sits k positions earlier.
struct Crc32cTables {
  uint32_t t[8][256];
};

constexpr Crc32cTables makeTables() {
  Crc32cTables tb{};
  for (uint32_t i = 0; i < 256; ++i) {
    uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1) ? (c >> 1) ^ 0x82F63B78u : c >> 1;
    tb.t[0][i] = c;
  }
  for (uint32_t i = 0; i < 256; ++i)
    for (int k = 1; k < 8; ++k) tb.t[k][i] = (tb.t[k - 1][i] >> 8) ^ tb.t[0][tb.t[k - 1][i] & 0xFF];
  return tb;
}

constexpr Crc32cTables kCrc = makeTables();

using detail::get;

std::string at(const std::string& name, const std::string& what, uint64_t offset) {
  return name + ": " + what + " at offset " + std::to_string(offset) + ": ";
}

core::Status corrupt(std::string& err, std::string msg) {
  err = std::move(msg);
  return core::Status::Corrupt;
}

// a + b <= limit without overflow.
bool fits(uint64_t offset, uint64_t size, uint64_t limit) {
  return size <= limit && offset <= limit - size;
}

}  // namespace

std::string tagToString(uint32_t tag) {
  char c[4];
  std::memcpy(c, &tag, 4);
  bool printable = true;
  for (char ch : c) printable = printable && ch >= 0x20 && ch < 0x7F;
  if (printable) return std::string(c, 4);
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%08X", tag);
  return buf;
}

#if defined(__x86_64__)
// SSE4.2's CRC32 instruction computes CRC32C (the Castagnoli polynomial,
// reflected), the same function as the tables. The loader checks a blob's CRC
// before decoding it, so the CRC's cost is in every cell load
// (`blvd bench decode` measures the whole decode).
namespace {
__attribute__((target("sse4.2"))) uint32_t crc32cSse42(const uint8_t* p, size_t size, uint32_t crc) {
  uint64_t c = ~crc;
  while (size >= 8) {
    uint64_t v;
    std::memcpy(&v, p, 8);
    c = _mm_crc32_u64(c, v);
    p += 8;
    size -= 8;
  }
  auto c32 = static_cast<uint32_t>(c);
  while (size--) c32 = _mm_crc32_u8(c32, *p++);
  return ~c32;
}
const bool kHaveSse42 = __builtin_cpu_supports("sse4.2");
}  // namespace
#endif

bool detail::crc32cAccelerated() {
#if defined(__x86_64__)
  return kHaveSse42;
#else
  return false;
#endif
}

uint32_t crc32c(const void* data, size_t size, uint32_t crc) {
#if defined(__x86_64__)
  if (kHaveSse42) return crc32cSse42(static_cast<const uint8_t*>(data), size, crc);
#endif
  return detail::crc32cTables(data, size, crc);
}

uint32_t detail::crc32cTables(const void* data, size_t size, uint32_t crc) {
  const auto* p = static_cast<const uint8_t*>(data);
  crc = ~crc;
  while (size >= 8) {
    uint32_t lo, hi;
    std::memcpy(&lo, p, 4);
    std::memcpy(&hi, p + 4, 4);
    lo ^= crc;
    crc = kCrc.t[7][lo & 0xFF] ^ kCrc.t[6][(lo >> 8) & 0xFF] ^ kCrc.t[5][(lo >> 16) & 0xFF] ^
          kCrc.t[4][lo >> 24] ^ kCrc.t[3][hi & 0xFF] ^ kCrc.t[2][(hi >> 8) & 0xFF] ^
          kCrc.t[1][(hi >> 16) & 0xFF] ^ kCrc.t[0][hi >> 24];
    p += 8;
    size -= 8;
  }
  while (size--) crc = (crc >> 8) ^ kCrc.t[0][(crc ^ *p++) & 0xFF];
  return ~crc;
}

namespace detail {

uint32_t headerCrc(const uint8_t* header, size_t header_size) {
  // The CRC field itself counts as zero, so the writer can fill it last.
  static const uint8_t kZero[4] = {0, 0, 0, 0};
  uint32_t c = crc32c(header, hdr::kCrc);
  c = crc32c(kZero, 4, c);
  return crc32c(header + hdr::kCrc + 4, header_size - hdr::kCrc - 4, c);
}

}  // namespace detail

core::Status parseHeader(const uint8_t* data, size_t size, uint64_t file_size,
                         const std::string& name, HeaderLayout& out, std::string& err) {
  namespace h = detail::hdr;
  if (size < sizeof kMagic || std::memcmp(data, kMagic, sizeof kMagic) != 0)
    return corrupt(err, name + ": not a blvd package (bad magic at offset 0)");
  if (size < kHeaderSize)
    return corrupt(err, at(name, "header", 0) + "file is " + std::to_string(file_size) +
                            " bytes, shorter than the " + std::to_string(kHeaderSize) +
                            "-byte header (truncated)");
  const uint32_t header_size = get<uint32_t>(data + h::kHeaderSize);
  if (header_size < kHeaderSize || header_size % kAlignment != 0 || header_size > file_size)
    return corrupt(err, at(name, "header", h::kHeaderSize) + "header size " +
                            std::to_string(header_size) + " is invalid (file is " +
                            std::to_string(file_size) + " bytes)");
  if (header_size > size)
    return corrupt(err, at(name, "header", h::kHeaderSize) + "header size " +
                            std::to_string(header_size) + " exceeds the " + std::to_string(size) +
                            " bytes available");
  const uint32_t stored_crc = get<uint32_t>(data + h::kCrc);
  const uint32_t actual_crc = detail::headerCrc(data, header_size);
  if (stored_crc != actual_crc) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "header checksum mismatch (stored 0x%08X, computed 0x%08X)",
                  stored_crc, actual_crc);
    return corrupt(err, at(name, "header", h::kCrc) + buf);
  }
  // Version after the CRC: bytes 0..23 keep their layout in every major
  // version (spec), so a bit flip here reads as corruption, and only an intact
  // header from another major version is reported as Unsupported.
  PackageHeader& ph = out.header;
  ph.version_major = get<uint16_t>(data + h::kVersionMajor);
  ph.version_minor = get<uint16_t>(data + h::kVersionMinor);
  if (ph.version_major != kVersionMajor) {
    err = at(name, "header", h::kVersionMajor) + "package format version " +
          std::to_string(ph.version_major) + "." + std::to_string(ph.version_minor) +
          ", this build reads " + std::to_string(kVersionMajor) + ".x";
    return core::Status::Unsupported;
  }
  out.header_size = header_size;
  out.file_size = get<uint64_t>(data + h::kFileSize);
  out.directory_offset = get<uint64_t>(data + h::kDirOffset);
  out.directory_count = get<uint32_t>(data + h::kDirCount);
  out.directory_crc = get<uint32_t>(data + h::kDirCrc);
  ph.origin_lat = get<double>(data + h::kOriginLat);
  ph.origin_lon = get<double>(data + h::kOriginLon);
  ph.origin_h = get<double>(data + h::kOriginH);
  for (int i = 0; i < 2; ++i) {
    ph.bounds_min[i] = get<float>(data + h::kBoundsMin + 4 * i);
    ph.bounds_max[i] = get<float>(data + h::kBoundsMax + 4 * i);
  }
  ph.junction_count = get<uint32_t>(data + h::kJunctionCount);
  ph.cell_count = get<uint32_t>(data + h::kCellCount);
  ph.block_count = get<uint32_t>(data + h::kBlockCount);
  ph.building_count = get<uint32_t>(data + h::kBuildingCount);
  ph.triangle_count = get<uint64_t>(data + h::kTriangleCount);
  ph.max_block_blob_bytes = get<uint32_t>(data + h::kMaxBlockBlob);
  ph.max_cell_blob_bytes = get<uint32_t>(data + h::kMaxCellBlob);
  ph.source_bytes = get<uint64_t>(data + h::kSourceBytes);
  ph.max_block_lod0_vertices = get<uint32_t>(data + h::kMaxBlockLod0Vertices);
  ph.max_block_lod0_triangles = get<uint32_t>(data + h::kMaxBlockLod0Triangles);
  ph.max_block_vertices = get<uint32_t>(data + h::kMaxBlockVertices);
  ph.max_block_triangles = get<uint32_t>(data + h::kMaxBlockTriangles);
  ph.max_cell_local_blocks = get<uint32_t>(data + h::kMaxCellLocalBlocks);
  ph.max_cell_local_lod0_vertices = get<uint32_t>(data + h::kMaxCellLocalLod0Vertices);
  ph.max_cell_local_lod0_triangles = get<uint32_t>(data + h::kMaxCellLocalLod0Triangles);
  ph.max_cell_local_vertices = get<uint32_t>(data + h::kMaxCellLocalVertices);
  ph.max_cell_local_triangles = get<uint32_t>(data + h::kMaxCellLocalTriangles);
  ph.max_cell_impostor_layers = get<uint32_t>(data + h::kMaxCellImpostorLayers);
  ph.max_cell_local_blob_bytes = get<uint64_t>(data + h::kMaxCellLocalBlobBytes);
  ph.max_cell_impostor_blob_bytes = get<uint64_t>(data + h::kMaxCellImpostorBlobBytes);
  ph.max_cell_impostor_texture_bytes = get<uint64_t>(data + h::kMaxCellImpostorTextureBytes);
  ph.max_cell_impostor_vertices = get<uint32_t>(data + h::kMaxCellImpostorVertices);
  ph.max_cell_impostor_triangles = get<uint32_t>(data + h::kMaxCellImpostorTriangles);
  ph.max_impostor_texture_bytes = get<uint32_t>(data + h::kMaxImpostorTextureBytes);
  ph.max_impostor_texture_width = get<uint16_t>(data + h::kMaxImpostorTextureWidth);
  ph.max_impostor_texture_height = get<uint16_t>(data + h::kMaxImpostorTextureHeight);
  ph.impostor_atlas_width = get<uint16_t>(data + h::kImpostorAtlasWidth);
  ph.impostor_atlas_height = get<uint16_t>(data + h::kImpostorAtlasHeight);
  ph.impostor_atlas_etc2_height = get<uint16_t>(data + h::kImpostorAtlasEtc2Height);
  ph.max_blob_contents_bytes = get<uint32_t>(data + h::kMaxBlobContents);

  if (out.file_size != file_size)
    return corrupt(err, at(name, "header", h::kFileSize) + "header records " +
                            std::to_string(out.file_size) + " bytes but the file has " +
                            std::to_string(file_size) +
                            (file_size < out.file_size ? " (truncated)" : " (trailing bytes)"));
  // A checksum only proves the writer meant these values; the runtime plans
  // its frame from them, so refuse nonsense too.
  if (!(std::isfinite(ph.origin_lat) && std::fabs(ph.origin_lat) <= 90 &&
        std::isfinite(ph.origin_lon) && std::fabs(ph.origin_lon) <= 180 &&
        std::isfinite(ph.origin_h)))
    return corrupt(err, at(name, "header", h::kOriginLat) + "geodetic origin out of range");
  for (int i = 0; i < 2; ++i)
    if (!(std::isfinite(ph.bounds_min[i]) && std::isfinite(ph.bounds_max[i]) &&
          ph.bounds_min[i] <= ph.bounds_max[i]))
      return corrupt(err, at(name, "header", h::kBoundsMin) + "bounds are not finite or min > max");
  if (ph.max_blob_contents_bytes > kMaxBlobContentsBytes)
    return corrupt(err, at(name, "header", h::kMaxBlobContents) + "largest blob of " +
                            std::to_string(ph.max_blob_contents_bytes) + " bytes is over the " +
                            std::to_string(kMaxBlobContentsBytes) + " a reader accepts");

  const uint64_t dir_bytes = uint64_t{out.directory_count} * kDirEntrySize;
  if (out.directory_offset % kAlignment != 0 || out.directory_offset < header_size ||
      !fits(out.directory_offset, dir_bytes, file_size))
    return corrupt(err, at(name, "directory", out.directory_offset) + "directory of " +
                            std::to_string(out.directory_count) + " entries (" +
                            std::to_string(dir_bytes) + " bytes) does not fit in the file (" +
                            std::to_string(file_size) + " bytes) or is misplaced");
  return core::Status::Ok;
}

std::vector<PoolSizingField> poolSizing(const PackageHeader& h) {
  return {
      {"max_block_blob_bytes", h.max_block_blob_bytes},
      {"max_cell_blob_bytes", h.max_cell_blob_bytes},
      {"max_block_lod0_vertices", h.max_block_lod0_vertices},
      {"max_block_lod0_triangles", h.max_block_lod0_triangles},
      {"max_block_vertices", h.max_block_vertices},
      {"max_block_triangles", h.max_block_triangles},
      {"max_cell_local_blocks", h.max_cell_local_blocks},
      {"max_cell_local_lod0_vertices", h.max_cell_local_lod0_vertices},
      {"max_cell_local_lod0_triangles", h.max_cell_local_lod0_triangles},
      {"max_cell_local_vertices", h.max_cell_local_vertices},
      {"max_cell_local_triangles", h.max_cell_local_triangles},
      {"max_cell_impostor_layers", h.max_cell_impostor_layers},
      {"max_cell_local_blob_bytes", h.max_cell_local_blob_bytes},
      {"max_cell_impostor_blob_bytes", h.max_cell_impostor_blob_bytes},
      {"max_cell_impostor_texture_bytes", h.max_cell_impostor_texture_bytes},
      {"max_cell_impostor_vertices", h.max_cell_impostor_vertices},
      {"max_cell_impostor_triangles", h.max_cell_impostor_triangles},
      {"max_impostor_texture_bytes", h.max_impostor_texture_bytes},
      {"max_impostor_texture_width", h.max_impostor_texture_width},
      {"max_impostor_texture_height", h.max_impostor_texture_height},
      {"impostor_atlas_width", h.impostor_atlas_width},
      {"impostor_atlas_height", h.impostor_atlas_height},
      {"impostor_atlas_etc2_height", h.impostor_atlas_etc2_height},
  };
}

core::Status parseDirectory(const uint8_t* data, size_t size, const HeaderLayout& layout,
                            const std::string& name, std::vector<SectionInfo>& out,
                            std::string& err) {
  namespace d = detail::dir;
  out.clear();
  const uint64_t dir_off = layout.directory_offset;
  if (size != uint64_t{layout.directory_count} * kDirEntrySize)
    return corrupt(err, at(name, "directory", dir_off) + "expected " +
                            std::to_string(uint64_t{layout.directory_count} * kDirEntrySize) +
                            " bytes, got " + std::to_string(size));
  const uint32_t crc = crc32c(data, size);
  if (crc != layout.directory_crc) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "directory checksum mismatch (stored 0x%08X, computed 0x%08X)",
                  layout.directory_crc, crc);
    return corrupt(err, at(name, "directory", dir_off) + buf);
  }
  const uint64_t dir_end = dir_off + size;
  out.reserve(layout.directory_count);
  for (uint32_t i = 0; i < layout.directory_count; ++i) {
    const uint8_t* e = data + size_t{i} * kDirEntrySize;
    SectionInfo s;
    s.tag = get<uint32_t>(e + d::kTag);
    s.offset = get<uint64_t>(e + d::kOffset);
    s.size = get<uint64_t>(e + d::kSize);
    s.crc = get<uint32_t>(e + d::kCrc);
    const std::string where = "section " + tagToString(s.tag);
    if (s.offset % kAlignment != 0)
      return corrupt(err, at(name, where, s.offset) + "offset is not " +
                              std::to_string(kAlignment) + "-byte aligned");
    if (!fits(s.offset, s.size, layout.file_size))
      return corrupt(err, at(name, where, s.offset) + "length " + std::to_string(s.size) +
                              " runs past end of file (" + std::to_string(layout.file_size) +
                              " bytes)");
    const bool hits_header = s.size > 0 && s.offset < layout.header_size;
    const bool hits_directory = s.size > 0 && size > 0 && s.offset < dir_end && s.offset + s.size > dir_off;
    if (hits_header || hits_directory)
      return corrupt(err, at(name, where, s.offset) + "overlaps the " +
                              (hits_header ? "header" : "directory"));
    for (const SectionInfo& o : out)
      if (o.tag == s.tag)
        return corrupt(err, at(name, where, s.offset) + "tag appears twice in the directory");
    out.push_back(s);
  }
  // Overlap between sections: sort a copy by offset, neighbours must not touch.
  std::vector<SectionInfo> sorted = out;
  std::sort(sorted.begin(), sorted.end(),
            [](const SectionInfo& a, const SectionInfo& b) { return a.offset < b.offset; });
  const SectionInfo* prev = nullptr;
  for (const SectionInfo& s : sorted) {
    if (s.size == 0) continue;
    if (prev && s.offset < prev->offset + prev->size)
      return corrupt(err, at(name, "section " + tagToString(s.tag), s.offset) + "overlaps section " +
                              tagToString(prev->tag));
    prev = &s;
  }
  return core::Status::Ok;
}

core::Status parseBlobIndex(const uint8_t* data, size_t size, const SectionInfo& index,
                            const SectionInfo& blob_data, uint32_t max_contents, const std::string& name,
                            std::vector<BlobInfo>& out, std::string& err) {
  namespace b = detail::blob;
  out.clear();
  const std::string where = "section " + tagToString(index.tag);
  if (size < kBlobIndexPrefix)
    return corrupt(err, at(name, where, index.offset) + "blob index is " + std::to_string(size) +
                            " bytes, shorter than its " + std::to_string(kBlobIndexPrefix) +
                            "-byte prefix");
  const uint32_t count = get<uint32_t>(data);
  const uint32_t entry_size = get<uint32_t>(data + 4);
  // Entries may grow in a later minor version (new fields at the end).
  if (entry_size < kBlobEntrySize || entry_size % 4 != 0)
    return corrupt(err, at(name, where, index.offset + 4) + "blob entry size " +
                            std::to_string(entry_size) + " is invalid");
  if (uint64_t{count} * entry_size != size - kBlobIndexPrefix)
    return corrupt(err, at(name, where, index.offset) + std::to_string(count) + " entries of " +
                            std::to_string(entry_size) + " bytes do not fill the " +
                            std::to_string(size) + "-byte blob index");
  out.reserve(count);
  for (uint32_t i = 0; i < count; ++i) {
    const uint64_t entry_off = kBlobIndexPrefix + uint64_t{i} * entry_size;
    const uint8_t* e = data + entry_off;
    BlobInfo bi;
    bi.offset = get<uint64_t>(e + b::kOffset);
    bi.size = get<uint64_t>(e + b::kSize);
    bi.crc = get<uint32_t>(e + b::kCrc);
    bi.flags = get<uint32_t>(e + b::kFlags);
    bi.contents_size = get<uint64_t>(e + b::kContents);
    const std::string blob_where = "blob " + std::to_string(i);
    const std::string entry_at = " (index entry at " + std::to_string(index.offset + entry_off) + ")";
    if (bi.offset % kAlignment != 0)
      return corrupt(err, at(name, blob_where, bi.offset) + "offset is not " +
                              std::to_string(kAlignment) + "-byte aligned" + entry_at);
    if (bi.offset < blob_data.offset ||
        !fits(bi.offset - blob_data.offset, bi.size, blob_data.size))
      return corrupt(err, at(name, blob_where, bi.offset) + "length " + std::to_string(bi.size) +
                              " lies outside section " + tagToString(blob_data.tag) + " [" +
                              std::to_string(blob_data.offset) + ", " +
                              std::to_string(blob_data.offset + blob_data.size) + ")" + entry_at);
    if (!validBlobFlags(bi.flags))
      return corrupt(err, at(name, blob_where, bi.offset) + "unknown flags " + std::to_string(bi.flags) + entry_at);
    if ((bi.flags & kBlobZstd) == 0 && bi.contents_size != bi.size)
      return corrupt(err, at(name, blob_where, bi.offset) + "stored as is, but its contents are " +
                              std::to_string(bi.contents_size) + " bytes and it is " + std::to_string(bi.size) +
                              entry_at);
    if (bi.contents_size > max_contents)
      return corrupt(err, at(name, blob_where, bi.offset) + "contents of " + std::to_string(bi.contents_size) +
                              " bytes, more than the header's largest, " + std::to_string(max_contents) + entry_at);
    out.push_back(bi);
  }
  return core::Status::Ok;
}

}  // namespace blvd::package
