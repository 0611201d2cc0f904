#include "graph/terrain_table.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/bytes.h"
#include "core/status.h"

namespace blvd::graph {
namespace {

constexpr double kMaxExtentM = 1e7;  // a root tile larger than a continent is corrupt

std::string checkLayout(const TerrainLayout& l) {
  if (l.levels < 1 || l.levels > kTerrainMaxLevels)
    return "levels " + std::to_string(l.levels) + " outside 1.." + std::to_string(kTerrainMaxLevels);
  if (l.grid < kTerrainMinGrid || l.grid > kTerrainMaxGrid)
    return "grid " + std::to_string(l.grid) + " outside " + std::to_string(kTerrainMinGrid) + ".." +
           std::to_string(kTerrainMaxGrid);
  if (!std::isfinite(l.west) || !std::isfinite(l.south) || std::abs(l.west) > kMaxExtentM ||
      std::abs(l.south) > kMaxExtentM || !(l.size > 0 && l.size <= kMaxExtentM))
    return "extent is not finite or empty";
  if (!std::isfinite(l.base_m) || std::abs(l.base_m) > 1e4f || !(l.step_m > 0 && l.step_m < 1.f))
    return "height steps are not finite, positive and under a metre";
  for (uint32_t k = 0; k < kTerrainMaxLevels; ++k)
    if (!std::isfinite(l.level_error_m[k]) || l.level_error_m[k] < 0 || (k >= l.levels && l.level_error_m[k] != 0))
      return "level " + std::to_string(k) + "'s error is negative, not finite, or set past the levels";
  return {};
}

std::string checkRecord(const TerrainRecord& r, uint32_t blob_count) {
  if (r.blob >= blob_count) return "blob " + std::to_string(r.blob) + " past the package's " + std::to_string(blob_count);
  if (!std::isfinite(r.error_m) || r.error_m < 0) return "error is negative or not finite";
  if (!std::isfinite(r.min_m) || !std::isfinite(r.max_m) || r.min_m > r.max_m || std::abs(r.min_m) > 1e4f ||
      std::abs(r.max_m) > 1e4f)
    return "heights are not finite, ordered and within 10 km";
  return {};
}

}  // namespace

uint64_t TerrainLayout::tiles() const { return terrainFirstOfLevel(levels); }

uint64_t terrainFirstOfLevel(uint32_t level) { return ((uint64_t(1) << (2 * level)) - 1) / 3; }

uint32_t terrainIndex(TerrainTile t) {
  return uint32_t(terrainFirstOfLevel(t.level) + (uint64_t(t.y) << t.level) + t.x);
}

TerrainTile terrainTileAt(uint32_t index) {
  TerrainTile t;
  while (terrainFirstOfLevel(t.level + 1) <= index) ++t.level;
  const uint64_t i = index - terrainFirstOfLevel(t.level);
  t.x = uint32_t(i & ((uint64_t(1) << t.level) - 1));
  t.y = uint32_t(i >> t.level);
  return t;
}

uint32_t terrainChild(uint32_t index, uint32_t k) {
  const TerrainTile t = terrainTileAt(index);
  return terrainIndex({t.level + 1, 2 * t.x + (k & 1), 2 * t.y + (k >> 1)});
}

uint32_t terrainParent(uint32_t index) {
  const TerrainTile t = terrainTileAt(index);
  return terrainIndex({t.level - 1, t.x / 2, t.y / 2});
}

std::vector<uint8_t> serializeTerrain(const TerrainLayout& layout, const std::vector<TerrainRecord>& records) {
  std::string why = checkLayout(layout);
  if (why.empty() && records.size() != layout.tiles())
    why = std::to_string(records.size()) + " records for a tree of " + std::to_string(layout.tiles()) + " tiles";
  for (size_t i = 0; why.empty() && i < records.size(); ++i)
    if (std::string w = checkRecord(records[i], 0xffffffffu); !w.empty()) why = "tile " + std::to_string(i) + ": " + w;
  if (!why.empty()) throw core::Error(core::Status::InvalidArg, "terrain section: " + why);
  core::ByteWriter w;
  w.put<uint32_t>(kTerrainVersion);
  w.put<uint32_t>(layout.grid);
  w.put<uint32_t>(layout.levels);
  w.put<uint32_t>(uint32_t(records.size()));
  w.put<double>(layout.west);
  w.put<double>(layout.south);
  w.put<double>(layout.size);
  w.put<float>(layout.base_m);
  w.put<float>(layout.step_m);
  for (float e : layout.level_error_m) w.put<float>(e);
  for (const TerrainRecord& r : records) {
    w.put<uint32_t>(r.blob);
    w.put<float>(r.error_m);
    w.put<float>(r.min_m);
    w.put<float>(r.max_m);
  }
  return std::move(w.bytes());
}

TerrainLayout parseTerrainHeader(const uint8_t* data, size_t size, uint64_t file_offset) {
  core::ByteReader r(data, size, "terrain section TERR", file_offset);
  const uint32_t version = r.get<uint32_t>();
  if (version != kTerrainVersion) r.fail("unknown version " + std::to_string(version), 0);
  TerrainLayout l;
  l.grid = r.get<uint32_t>();
  l.levels = r.get<uint32_t>();
  const uint32_t count = r.get<uint32_t>();
  l.west = r.get<double>();
  l.south = r.get<double>();
  l.size = r.get<double>();
  l.base_m = r.get<float>();
  l.step_m = r.get<float>();
  for (float& e : l.level_error_m) e = r.get<float>();
  if (const std::string why = checkLayout(l); !why.empty()) r.fail(why, 4);
  if (count != l.tiles()) r.fail(std::to_string(count) + " records for a tree of " + std::to_string(l.tiles()) + " tiles", 12);
  if (uint64_t(count) * kTerrainRecordBytes != r.remaining())
    r.fail("truncated or overlong: " + std::to_string(r.remaining()) + " bytes for " + std::to_string(count) + " records");
  return l;
}

std::string parseTerrainRecord(const uint8_t* p, uint32_t blob_count, TerrainRecord& out) {
  std::memcpy(&out.blob, p, 4);
  std::memcpy(&out.error_m, p + 4, 4);
  std::memcpy(&out.min_m, p + 8, 4);
  std::memcpy(&out.max_m, p + 12, 4);
  return checkRecord(out, blob_count);
}

std::vector<uint8_t> encodeTerrainHeights(const float* heights, const TerrainLayout& l) {
  std::vector<uint8_t> out(size_t(l.grid) * l.grid * 2);
  for (size_t i = 0; i < size_t(l.grid) * l.grid; ++i) {
    const double t = (double(heights[i]) - l.base_m) / l.step_m;
    const auto q = uint16_t(std::lround(std::clamp(t, 0.0, 65535.0)));
    out[2 * i] = uint8_t(q & 0xff);
    out[2 * i + 1] = uint8_t(q >> 8);
  }
  return out;
}

bool decodeTerrainHeights(const uint8_t* blob, size_t size, const TerrainLayout& l, float* out) {
  if (size != size_t(l.grid) * l.grid * 2) return false;
  for (size_t i = 0; i < size_t(l.grid) * l.grid; ++i)
    out[i] = float(double(l.base_m) + double(l.step_m) * (unsigned(blob[2 * i]) | unsigned(blob[2 * i + 1]) << 8));
  return true;
}

}  // namespace blvd::graph
