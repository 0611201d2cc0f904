#include "graph/block_table.h"

#include <cmath>

#include "core/bytes.h"

namespace blvd::graph {

std::vector<uint8_t> serializeBlocks(const std::vector<BlockRecord>& blocks) {
  core::ByteWriter w;
  w.put<uint32_t>(1);  // record version
  w.put<uint32_t>(static_cast<uint32_t>(blocks.size()));
  for (const BlockRecord& b : blocks) {
    w.put(b.blob);
    w.put(b.building_count);
    w.put(b.triangle_count);
    w.put(b.flags);
    for (float v : b.bbox_min) w.put(v);
    for (float v : b.bbox_max) w.put(v);
  }
  return std::move(w.bytes());
}

void parseBlocks(const uint8_t* data, size_t size, uint64_t file_offset, uint32_t blob_count,
                 std::vector<BlockRecord>& out) {
  core::ByteReader r(data, size, "block section BLCK", file_offset);
  if (r.get<uint32_t>() != 1) r.fail("unknown block record version");
  out.resize(r.getCount(40));
  for (BlockRecord& b : out) {
    const size_t at = r.pos();
    b.blob = r.get<uint32_t>();
    b.building_count = r.get<uint32_t>();
    b.triangle_count = r.get<uint32_t>();
    b.flags = r.get<uint32_t>();
    for (float& v : b.bbox_min) v = r.get<float>();
    for (float& v : b.bbox_max) v = r.get<float>();
    if (b.blob != 0xffffffffu && b.blob >= blob_count) r.fail("blob index out of range", at);
    for (int i = 0; i < 3; ++i)
      if (!std::isfinite(b.bbox_min[i]) || !std::isfinite(b.bbox_max[i]) || b.bbox_min[i] > b.bbox_max[i])
        r.fail("bad bounding box", at);
  }
}

}  // namespace blvd::graph
