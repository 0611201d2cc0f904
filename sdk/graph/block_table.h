// The BLCK section: one fixed-size record per block (face of the street map)
// pointing at the block's geometry blob (GLB) with its bounds and, per level of
// detail, the counts the decoder will produce and the simplification error,
// so the runtime can plan its pools, cull and choose a level (Marvie: the level
// whose polygon count is nearest the block's share of the budget) without
// decoding anything. docs/package-format.md has the byte layout.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace blvd::graph {

// Levels of detail a block can have: the full mesh plus up to three
// simplified ones (docs/decisions/0004-lod-chain.md).
constexpr uint32_t kMaxBlockLods = 4;

struct BlockRecord {
  uint32_t blob = 0xffffffffu;  // blob index of the block's GLB (all its levels); none if empty
  uint32_t building_count = 0;
  uint32_t flags = 0;           // kBlockUnbounded
  float bbox_min[3] = {0, 0, 0};  // glTF axes (x east, y up, z south), metres, of level 0
  float bbox_max[3] = {0, 0, 0};
  // Levels in the GLB: 0 for an empty block (no blob), else 1..kMaxBlockLods.
  // Level 0 is the full mesh; each further level has strictly fewer triangles.
  uint32_t lod_count = 0;
  // Per level k < lod_count: exactly what stream::City::decodeBlock(b, k)
  // returns (vertices = MeshData::vertexCount(), triangles = triangleCount()),
  // and the simplification error in metres (0 for level 0, non-decreasing, finite).
  // Entries k >= lod_count are 0.
  uint32_t triangles[kMaxBlockLods] = {0, 0, 0, 0};
  uint32_t vertices[kMaxBlockLods] = {0, 0, 0, 0};
  float error_m[kMaxBlockLods] = {0, 0, 0, 0};
  // Level 0's counts (== triangles[0], vertices[0]); kept for readability of
  // the many callers that want the full model.
  uint32_t triangle_count = 0;
  uint32_t vertex_count = 0;

  // Sums over all levels (what a pool holding every level of the block needs).
  uint64_t allTriangles() const;
  uint64_t allVertices() const;
};
enum BlockFlags : uint32_t { kBlockUnbounded = 1 };

// Record layout version written by serializeBlocks (the BLCK section starts
// with it); 2 since package format 2.0.
constexpr uint32_t kBlockTableVersion = 2;

// Throws core::Error(InvalidArg) when a record breaks the rules above (the
// bake must never write what parseBlocks would refuse).
std::vector<uint8_t> serializeBlocks(const std::vector<BlockRecord>& blocks);
// Throws core::Error(Corrupt) naming the offset: unknown version, truncation,
// blob >= blob_count, bad bounds, or level counts/errors breaking the rules above.
void parseBlocks(const uint8_t* data, size_t size, uint64_t file_offset, uint32_t blob_count,
                 std::vector<BlockRecord>& out);

// The same a record at a time, for a reader that pages the table: the
// section's header (throws as parseBlocks does), then one record of
// `record_size` bytes at data + records_at + i × record_size, checked as
// parseBlocks checks it (returns why not, or empty).
struct BlockTableShape {
  uint32_t record_size = 0, count = 0;
  size_t records_at = 0;
};
BlockTableShape parseBlockTableShape(const uint8_t* data, size_t size, uint64_t file_offset);
std::string parseBlockRecord(const uint8_t* record, uint32_t blob_count, BlockRecord& out);

}  // namespace blvd::graph
