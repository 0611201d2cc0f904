#include "graph/block_table.h"

#include <cmath>
#include <string>

#include "core/bytes.h"
#include "core/status.h"

namespace blvd::graph {
namespace {

// Bytes of one record in version 2 (docs/package-format.md, BLCK).
constexpr uint32_t kRecordSize = 88;
// No level may promise more than the GLB decoder will produce
// (package::kMaxDecodedVertices), so a corrupt count cannot size a pool.
constexpr uint32_t kMaxLevelElements = uint32_t{1} << 24;

// Empty when `b` keeps the rules in block_table.h, else why not.
std::string check(const BlockRecord& b, uint32_t blob_count) {
  if (b.blob != 0xffffffffu && b.blob >= blob_count) return "blob index out of range";
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(b.bbox_min[i]) || !std::isfinite(b.bbox_max[i]) || b.bbox_min[i] > b.bbox_max[i])
      return "bad bounding box";
  if (b.lod_count > kMaxBlockLods) return "lod_count " + std::to_string(b.lod_count) + " > " + std::to_string(kMaxBlockLods);
  if ((b.lod_count == 0) != (b.blob == 0xffffffffu)) return "lod_count is 0 exactly when there is no blob";
  for (uint32_t k = 0; k < kMaxBlockLods; ++k) {
    const std::string lvl = "level " + std::to_string(k) + ": ";
    if (k >= b.lod_count) {
      if (b.triangles[k] || b.vertices[k] || b.error_m[k] != 0.f) return lvl + "counts past lod_count are not 0";
      continue;
    }
    if (b.triangles[k] == 0 || b.vertices[k] == 0) return lvl + "no triangles or no vertices";
    if (b.triangles[k] > kMaxLevelElements || b.vertices[k] > kMaxLevelElements) return lvl + "more than 2^24 elements";
    if (!std::isfinite(b.error_m[k]) || b.error_m[k] < 0.f) return lvl + "error is negative or not finite";
    if (k == 0 && b.error_m[0] != 0.f) return "level 0 has a simplification error";
    if (k > 0 && b.triangles[k] >= b.triangles[k - 1]) return lvl + "does not have fewer triangles than the level before";
    if (k > 0 && b.error_m[k] < b.error_m[k - 1]) return lvl + "error is smaller than the level before's";
  }
  return {};
}

}  // namespace

uint64_t BlockRecord::allTriangles() const {
  uint64_t n = 0;
  for (uint32_t k = 0; k < lod_count && k < kMaxBlockLods; ++k) n += triangles[k];
  return n;
}

uint64_t BlockRecord::allVertices() const {
  uint64_t n = 0;
  for (uint32_t k = 0; k < lod_count && k < kMaxBlockLods; ++k) n += vertices[k];
  return n;
}

std::vector<uint8_t> serializeBlocks(const std::vector<BlockRecord>& blocks) {
  core::ByteWriter w;
  w.put<uint32_t>(kBlockTableVersion);
  w.put<uint32_t>(kRecordSize);
  w.put<uint32_t>(static_cast<uint32_t>(blocks.size()));
  for (size_t i = 0; i < blocks.size(); ++i) {
    const BlockRecord& b = blocks[i];
    std::string why = check(b, 0xffffffffu);
    if (why.empty() && (b.triangle_count != b.triangles[0] || b.vertex_count != b.vertices[0]))
      why = "triangle_count/vertex_count differ from level 0's";
    if (!why.empty()) throw core::Error(core::Status::InvalidArg, "serializeBlocks: block " + std::to_string(i) + ": " + why);
    w.put(b.blob);
    w.put(b.building_count);
    w.put(b.flags);
    w.put(b.lod_count);
    for (float v : b.bbox_min) w.put(v);
    for (float v : b.bbox_max) w.put(v);
    for (uint32_t v : b.triangles) w.put(v);
    for (uint32_t v : b.vertices) w.put(v);
    for (float v : b.error_m) w.put(v);
  }
  return std::move(w.bytes());
}

BlockTableShape parseBlockTableShape(const uint8_t* data, size_t size, uint64_t file_offset) {
  core::ByteReader r(data, size, "block section BLCK", file_offset);
  const uint32_t version = r.get<uint32_t>();
  if (version != kBlockTableVersion)
    r.fail("block record version " + std::to_string(version) + ", this build reads " +
               std::to_string(kBlockTableVersion),
           0);
  // Later minor versions may append fields to a record; a reader skips them.
  const size_t at_size = r.pos();
  BlockTableShape t;
  t.record_size = r.get<uint32_t>();
  if (t.record_size < kRecordSize || t.record_size % 4)
    r.fail("record size " + std::to_string(t.record_size) + " is not a multiple of 4 >= " + std::to_string(kRecordSize),
           at_size);
  t.count = r.getCount(t.record_size);
  if (uint64_t{t.count} * t.record_size != r.remaining())
    r.fail(std::to_string(r.remaining() - uint64_t{t.count} * t.record_size) + " bytes after the last record");
  t.records_at = r.pos();
  return t;
}

std::string parseBlockRecord(const uint8_t* rec, uint32_t blob_count, BlockRecord& b) {
  core::ByteReader r(rec, kRecordSize, "block record");
  b.blob = r.get<uint32_t>();
  b.building_count = r.get<uint32_t>();
  b.flags = r.get<uint32_t>();
  b.lod_count = r.get<uint32_t>();
  for (float& v : b.bbox_min) v = r.get<float>();
  for (float& v : b.bbox_max) v = r.get<float>();
  for (uint32_t& v : b.triangles) v = r.get<uint32_t>();
  for (uint32_t& v : b.vertices) v = r.get<uint32_t>();
  for (float& v : b.error_m) v = r.get<float>();
  b.triangle_count = b.triangles[0];
  b.vertex_count = b.vertices[0];
  return check(b, blob_count);
}

void parseBlocks(const uint8_t* data, size_t size, uint64_t file_offset, uint32_t blob_count,
                 std::vector<BlockRecord>& out) {
  const BlockTableShape t = parseBlockTableShape(data, size, file_offset);
  out.resize(t.count);
  for (uint32_t i = 0; i < t.count; ++i) {
    const size_t at = t.records_at + size_t(i) * t.record_size;
    const std::string why = parseBlockRecord(data + at, blob_count, out[i]);
    if (!why.empty())
      core::ByteReader(data, size, "block section BLCK", file_offset).fail("block " + std::to_string(i) + ": " + why, at);
  }
}

}  // namespace blvd::graph
