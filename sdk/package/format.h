// The blvd package format, version 1.0: constants, the header the bake fills,
// and the pure parsers shared by the mmap reader and any range-request client.
//
// docs/package-format.md is the spec; this file and format.cpp implement it.
// Everything on disk is little-endian. Layout in one line:
//   [header 256 B][directory: 32 B per section][sections..., each 8-aligned]
// Blobs (GLB per block/cell) live in the BDAT section, located by the BIDX
// section, so one blob costs three small reads: header, directory, blob index
// entry (or one read when the first 16 KiB hold all three), then its range.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"

namespace blvd::package {

// Section tags are four ASCII bytes; on disk the bytes read left to right
// ("GRPH"), which is the value fourcc('G','R','P','H') stored little-endian.
// (Multi-character literals like 'GRPH' are implementation-defined and pack the
// other way round on GCC, so they are not used.)
constexpr uint32_t fourcc(char a, char b, char c, char d) {
  return static_cast<uint32_t>(static_cast<uint8_t>(a)) |
         (static_cast<uint32_t>(static_cast<uint8_t>(b)) << 8) |
         (static_cast<uint32_t>(static_cast<uint8_t>(c)) << 16) |
         (static_cast<uint32_t>(static_cast<uint8_t>(d)) << 24);
}

inline constexpr char kMagic[8] = {'B', 'L', 'V', 'D', 'P', 'K', 'G', '\0'};
// 2.0: BLCK records carry the levels of detail, IMPO layers their vertex
// counts, the header the pool sizing fields; 3.0: IMPO layers the run of the
// cell they serve; 3.2: TPCR, a CRC per table page; 3.3: the impostor atlas's
// size in the header; 4.0: blobs stored as zstd frames (BIDX flags and
// contents size, the header's largest contents); 5.0: Draco streams hold no
// POSITION-typed attribute; 6.0: blob frames with the built-in dictionary,
// impostor uv projected from the positions (docs/package-format.md).
inline constexpr uint16_t kVersionMajor = 6;  // a reader opens only its own major
inline constexpr uint16_t kVersionMinor = 0;  // minors add, never change (see spec)

inline constexpr uint32_t kSectionGraph = fourcc('G', 'R', 'P', 'H');         // street graph
inline constexpr uint32_t kSectionSpatialIndex = fourcc('S', 'I', 'D', 'X');  // graph spatial index
inline constexpr uint32_t kSectionCells = fourcc('C', 'E', 'L', 'L');         // cells directory
inline constexpr uint32_t kSectionBlocks = fourcc('B', 'L', 'C', 'K');        // blocks directory
inline constexpr uint32_t kSectionMeta = fourcc('M', 'E', 'T', 'A');          // bake metadata (JSON)
inline constexpr uint32_t kSectionVisibility = fourcc('P', 'V', 'S', 'A');    // per-cell PVS + coverage hints
inline constexpr uint32_t kSectionImpostors = fourcc('I', 'M', 'P', 'O');     // per-cell impostor layers
inline constexpr uint32_t kSectionCellTableIndex = fourcc('C', 'T', 'I', 'X');  // per-cell PVSA/IMPO offsets
inline constexpr uint32_t kSectionShard = fourcc('S', 'H', 'R', 'D');  // only in a bake shard file (bake/shard.h)
inline constexpr uint32_t kSectionElevation = fourcc('E', 'L', 'E', 'V');  // ground height of each graph point (terrain)
inline constexpr uint32_t kSectionTerrain = fourcc('T', 'E', 'R', 'R');    // terrain quadtree tiles (graph/terrain_table.h)
// Written by PackageWriter itself; addSection() refuses these three tags.
inline constexpr uint32_t kSectionBlobIndex = fourcc('B', 'I', 'D', 'X');  // blob offset/size/crc table
inline constexpr uint32_t kSectionBlobData = fourcc('B', 'D', 'A', 'T');   // the blobs themselves
inline constexpr uint32_t kSectionTablePages = fourcc('T', 'P', 'C', 'R');  // a CRC per table page (table_pages.h)

inline constexpr size_t kHeaderSize = 256;     // v1.0 header bytes; later minors may grow it
inline constexpr size_t kDirEntrySize = 32;    // one directory entry
inline constexpr size_t kBlobIndexPrefix = 8;  // BIDX: u32 count, u32 entry size
inline constexpr size_t kBlobEntrySize = 32;   // 4.0 BIDX entry; later minors may grow it
inline constexpr size_t kAlignment = 8;        // every section and blob starts 8-aligned
// BIDX flags: the blob's bytes are one zstd frame of its contents (4.0),
// made with the built-in dictionary (6.0, blob_dictionary.h; only with
// kBlobZstd).
inline constexpr uint32_t kBlobZstd = 1u;
inline constexpr uint32_t kBlobZstdDict = 2u;
inline constexpr bool validBlobFlags(uint32_t flags) {
  return (flags & ~(kBlobZstd | kBlobZstdDict)) == 0 && ((flags & kBlobZstdDict) == 0 || (flags & kBlobZstd) != 0);
}
// No blob's contents may exceed this (a reader refuses the package): a
// corrupt contents size must not make a reader allocate gigabytes.
inline constexpr uint64_t kMaxBlobContentsBytes = uint64_t{1} << 28;

// What the bake knows about the city and the runtime needs before it reads
// anything else. Plain data: PackageWriter::setHeader() copies it and
// PackageReader::header() returns what was read. The writer always stores
// kVersionMajor/kVersionMinor, whatever version_* say here.
struct PackageHeader {
  uint16_t version_major = kVersionMajor, version_minor = kVersionMinor;
  double origin_lat = 0, origin_lon = 0, origin_h = 0;  // geodetic origin of the local ENU frame
  float bounds_min[2] = {0, 0}, bounds_max[2] = {0, 0};  // local east/north metres
  uint32_t junction_count = 0, cell_count = 0, block_count = 0, building_count = 0;
  uint64_t triangle_count = 0;
  // Largest block blob (all its levels) and largest cell blob (one impostor
  // layer's GLB), bytes.
  uint32_t max_block_blob_bytes = 0, max_cell_blob_bytes = 0;
  uint64_t source_bytes = 0;  // bytes of the source .osm.pbf
  // Pool sizing (2.0): exact maxima over the package, so the runtime carves
  // its pools at create from the header alone. "Vertices"/"triangles" are
  // what decoding gives (the BLCK/IMPO counts); a cell's "local blocks" are
  // its CELL local-block list. docs/package-format.md defines each one.
  uint32_t max_block_lod0_vertices = 0, max_block_lod0_triangles = 0;  // one block, level 0
  uint32_t max_block_vertices = 0, max_block_triangles = 0;            // one block, its levels summed
  uint32_t max_cell_local_blocks = 0;                                  // most local blocks of one cell
  uint32_t max_cell_local_lod0_vertices = 0, max_cell_local_lod0_triangles = 0;  // summed over a cell's local blocks
  uint32_t max_cell_local_vertices = 0, max_cell_local_triangles = 0;  // same, every level of each
  uint64_t max_cell_local_blob_bytes = 0;                              // a cell's local blocks' blobs
  uint32_t max_cell_impostor_layers = 0;                               // layered + single of one cell
  uint32_t max_cell_impostor_vertices = 0, max_cell_impostor_triangles = 0;  // summed over a cell's layers
  uint64_t max_cell_impostor_blob_bytes = 0;                           // a cell's impostor blobs
  uint64_t max_cell_impostor_texture_bytes = 0;                        // a cell's layers' w × h × 4
  uint32_t max_impostor_texture_bytes = 0;                             // one layer's w × h × 4
  uint16_t max_impostor_texture_width = 0, max_impostor_texture_height = 0;  // over all layers
  // 3.3: the atlas a cell slot holds its impostor images in, packed by
  // render/slab_atlas.h, that every cell's fit (0 before 3.3, or no impostors).
  uint16_t impostor_atlas_width = 0, impostor_atlas_height = 0;
  // 5.1: the same cells packed on an ETC2 atlas's 32-texel grid, as wide as
  // impostor_atlas_width rounded up to 32 (render/slab_atlas.h); 0 before.
  uint16_t impostor_atlas_etc2_height = 0;
  // 4.0: the largest blob's contents (after decompression), bytes. The
  // writer fills it from its blobs, whatever setHeader() was given.
  uint32_t max_blob_contents_bytes = 0;
};

// The pool sizing fields by name (max_block_blob_bytes, max_cell_blob_bytes
// and the 2.0 ones, in header order), for `blvd pack info` and tests.
struct PoolSizingField {
  const char* name;
  uint64_t value;
};
std::vector<PoolSizingField> poolSizing(const PackageHeader& h);

// One directory entry (for `blvd pack info` and range clients).
struct SectionInfo {
  uint32_t tag = 0;
  uint64_t offset = 0;  // from the start of the file
  uint64_t size = 0;    // bytes, without the alignment padding after it
  uint32_t crc = 0;     // CRC32C of those bytes
};

// One BIDX entry. `offset` is from the start of the file, so a remote client
// turns it straight into an HTTP Range header.
struct BlobInfo {
  uint64_t offset = 0;
  uint64_t size = 0;           // bytes in the file (what a range request fetches)
  uint32_t crc = 0;            // CRC32C of those bytes
  uint32_t flags = 0;          // kBlobZstd, with kBlobZstdDict, or 0
  uint64_t contents_size = 0;  // bytes of the GLB (or heights) they hold: `size` when not compressed
};

// The header fields the reader needs to find everything else.
struct HeaderLayout {
  PackageHeader header;
  uint32_t header_size = kHeaderSize;
  uint64_t file_size = 0;
  uint64_t directory_offset = 0;
  uint32_t directory_count = 0;
  uint32_t directory_crc = 0;
};

// "GRPH", or "0x12345678" when the tag is not four printable characters.
std::string tagToString(uint32_t tag);

// CRC32C (Castagnoli, reflected polynomial 0x82F63B78), our own slice-by-8
// table implementation rather than zlib's crc32: CRC32C detects more error
// patterns at these lengths, is the checksum object stores use for range reads
// (so a CDN-side check can reuse it), and has CPU instructions on x86 (SSE4.2)
// and ARMv8 that a later fast path can use without changing the format.
// Chain calls by passing the previous result: crc32c(b, n, crc32c(a, m)).
uint32_t crc32c(const void* data, size_t size, uint32_t crc = 0);

// Parsers. They never read outside [data, data + size) and never throw; on
// failure they return Corrupt (or Unsupported for a newer major version) and
// set `err` to "<name>: <what> at offset <n>: <why>".

// `data` holds the first `size` bytes of the file; `file_size` is the whole
// file's size. Needs size >= header_size (256 for v1.0). Checks magic, header
// CRC, version, the recorded file size and that the directory fits.
core::Status parseHeader(const uint8_t* data, size_t size, uint64_t file_size,
                         const std::string& name, HeaderLayout& out, std::string& err);

// `data`/`size` are exactly the directory bytes (directory_count * 32 at
// directory_offset). Checks the directory CRC, then that every section is
// 8-aligned, inside the file, clear of header/directory/other sections, and
// that no tag repeats.
core::Status parseDirectory(const uint8_t* data, size_t size, const HeaderLayout& layout,
                            const std::string& name, std::vector<SectionInfo>& out,
                            std::string& err);

// `data`/`size` are the BIDX section's bytes (located by `index`); every blob
// must be 8-aligned and inside `blob_data` (the BDAT entry), carry no flag
// but kBlobZstd and kBlobZstdDict (the latter only with the former), and hold at most `max_contents` bytes of contents (the
// header's max_blob_contents_bytes). Does not check the BIDX section's own
// CRC (verify does that).
core::Status parseBlobIndex(const uint8_t* data, size_t size, const SectionInfo& index,
                            const SectionInfo& blob_data, uint32_t max_contents, const std::string& name,
                            std::vector<BlobInfo>& out, std::string& err);

}  // namespace blvd::package
