// Byte offsets of the on-disk structures (docs/package-format.md has the same
// tables) and little-endian load/store helpers. Private to sdk/package: the
// reader and writer must agree on these, nobody else should need them.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace blvd::package::detail {

template <typename T>
T get(const uint8_t* p) {
  static_assert(std::is_arithmetic_v<T>, "plain numbers only");
  T v;
  std::memcpy(&v, p, sizeof v);  // memcpy: fields need not be aligned in a fuzzed buffer
  return v;
}

template <typename T>
void put(uint8_t* p, T v) {
  static_assert(std::is_arithmetic_v<T>, "plain numbers only");
  std::memcpy(p, &v, sizeof v);
}

// crc32c() by slice-by-8 tables, the portable path (crc32c() takes the CPU's
// instruction where crc32cAccelerated() says it has one); for the tests that
// hold the two paths to the same answers.
uint32_t crc32cTables(const void* data, size_t size, uint32_t crc = 0);
bool crc32cAccelerated();

// CRC32C over header[0, header_size) with the CRC field read as zero.
uint32_t headerCrc(const uint8_t* header, size_t header_size);

namespace hdr {  // header, 256 bytes in 2.0
constexpr size_t kMagic = 0;          // char[8] "BLVDPKG\0"
constexpr size_t kVersionMajor = 8;   // u16
constexpr size_t kVersionMinor = 10;  // u16
constexpr size_t kHeaderSize = 12;    // u32, bytes covered by the header CRC
constexpr size_t kReserved0 = 16;     // u32, zero
constexpr size_t kCrc = 20;           // u32, CRC32C of the header with this field as 0
constexpr size_t kFileSize = 24;      // u64
constexpr size_t kDirOffset = 32;     // u64
constexpr size_t kDirCount = 40;      // u32
constexpr size_t kDirCrc = 44;        // u32
constexpr size_t kOriginLat = 48;     // f64
constexpr size_t kOriginLon = 56;     // f64
constexpr size_t kOriginH = 64;       // f64
constexpr size_t kBoundsMin = 72;     // f32[2]
constexpr size_t kBoundsMax = 80;     // f32[2]
constexpr size_t kJunctionCount = 88; // u32
constexpr size_t kCellCount = 92;     // u32
constexpr size_t kBlockCount = 96;    // u32
constexpr size_t kBuildingCount = 100;// u32
constexpr size_t kTriangleCount = 104;// u64
constexpr size_t kMaxBlockBlob = 112; // u32
constexpr size_t kMaxCellBlob = 116;  // u32
constexpr size_t kSourceBytes = 120;  // u64
// Pool sizing, 2.0.
constexpr size_t kMaxBlockLod0Vertices = 128;      // u32
constexpr size_t kMaxBlockLod0Triangles = 132;     // u32
constexpr size_t kMaxBlockVertices = 136;          // u32
constexpr size_t kMaxBlockTriangles = 140;         // u32
constexpr size_t kMaxCellLocalBlocks = 144;        // u32
constexpr size_t kMaxCellLocalLod0Vertices = 148;  // u32
constexpr size_t kMaxCellLocalLod0Triangles = 152; // u32
constexpr size_t kMaxCellLocalVertices = 156;      // u32
constexpr size_t kMaxCellLocalTriangles = 160;     // u32
constexpr size_t kMaxCellImpostorLayers = 164;     // u32
constexpr size_t kMaxCellLocalBlobBytes = 168;     // u64
constexpr size_t kMaxCellImpostorBlobBytes = 176;  // u64
constexpr size_t kMaxCellImpostorTextureBytes = 184;  // u64
constexpr size_t kMaxCellImpostorVertices = 192;   // u32
constexpr size_t kMaxCellImpostorTriangles = 196;  // u32
constexpr size_t kMaxImpostorTextureBytes = 200;   // u32
constexpr size_t kMaxImpostorTextureWidth = 204;   // u16
constexpr size_t kMaxImpostorTextureHeight = 206;  // u16
constexpr size_t kImpostorAtlasWidth = 208;        // u16, 3.3
constexpr size_t kImpostorAtlasHeight = 210;       // u16, 3.3
constexpr size_t kMaxBlobContents = 212;           // u32, 4.0
constexpr size_t kImpostorAtlasEtc2Height = 216;   // u16, 5.1
constexpr size_t kReservedTail = 218; // zero up to header_size
}  // namespace hdr

namespace dir {  // one 32-byte directory entry
constexpr size_t kTag = 0;       // u32
constexpr size_t kFlags = 4;     // u32, zero in v1.0
constexpr size_t kOffset = 8;    // u64
constexpr size_t kSize = 16;     // u64
constexpr size_t kCrc = 24;      // u32
constexpr size_t kReserved = 28; // u32, zero
}  // namespace dir

namespace blob {  // one 32-byte BIDX entry (4.0), after the 8-byte prefix
constexpr size_t kOffset = 0;     // u64
constexpr size_t kSize = 8;       // u64, bytes in the file
constexpr size_t kCrc = 16;       // u32, of those bytes
constexpr size_t kFlags = 20;     // u32, kBlobZstd (with kBlobZstdDict) or 0
constexpr size_t kContents = 24;  // u64, bytes of contents
}  // namespace blob

}  // namespace blvd::package::detail
