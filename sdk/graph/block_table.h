// The BLCK section: one fixed-size record per block (face of the street map)
// pointing at the block's geometry blob (GLB) with its counts and bounds, so
// the runtime can plan, cull and load blocks without decoding them.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace blvd::graph {

struct BlockRecord {
  uint32_t blob = 0xffffffffu;  // blob index of the block's GLB; none if empty
  uint32_t building_count = 0;
  uint32_t triangle_count = 0;
  uint32_t flags = 0;           // kBlockUnbounded
  float bbox_min[3] = {0, 0, 0};  // glTF axes (x east, y up, z south), metres
  float bbox_max[3] = {0, 0, 0};
};
enum BlockFlags : uint32_t { kBlockUnbounded = 1 };

std::vector<uint8_t> serializeBlocks(const std::vector<BlockRecord>& blocks);
// Throws core::Error(Corrupt) naming the offset; checks blob < blob_count.
void parseBlocks(const uint8_t* data, size_t size, uint64_t file_offset, uint32_t blob_count,
                 std::vector<BlockRecord>& out);

}  // namespace blvd::graph
