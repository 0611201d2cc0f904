#include "bake/block_blob.h"

#include <algorithm>
#include <chrono>
#include <limits>

#include "core/status.h"

namespace blvd::bake {

std::vector<uint8_t> encodeBlock(const geo::MeshData& mesh, const LodOptions& lod, const package::GlbOptions& glb,
                                 graph::BlockRecord& rec, LodStats& stats) {
  if (mesh.empty()) throw core::Error(core::Status::InvalidArg, "encodeBlock: empty mesh");
  for (int k = 0; k < 3; ++k) {
    rec.bbox_min[k] = std::numeric_limits<float>::max();
    rec.bbox_max[k] = -std::numeric_limits<float>::max();
  }
  for (size_t v = 0; v < mesh.positions.size(); v += 3)
    for (int k = 0; k < 3; ++k) {
      rec.bbox_min[k] = std::min(rec.bbox_min[k], mesh.positions[v + k]);
      rec.bbox_max[k] = std::max(rec.bbox_max[k], mesh.positions[v + k]);
    }

  const auto t0 = std::chrono::steady_clock::now();
  std::vector<LodLevel> levels = buildLodChain(mesh, lod);
  stats.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::vector<package::GlbMeshCounts> counts;
  std::vector<uint8_t> bytes;
  for (;;) {
    std::vector<geo::MeshData> meshes;
    for (const LodLevel& l : levels) meshes.push_back(l.mesh);
    bytes = package::encodeGlbLevels(meshes, glb, &counts);
    // Draco drops degenerate faces, so a level can lose its lead over the
    // one before once encoded; such a level goes and the rest are re-encoded
    // (the record promises strictly fewer triangles per level).
    size_t bad = 0;
    for (size_t k = 1; k < counts.size() && !bad; ++k)
      if (counts[k].triangles >= counts[k - 1].triangles || counts[k].triangles == 0) bad = k;
    if (!bad) break;
    levels.erase(levels.begin() + static_cast<ptrdiff_t>(bad));
    ++stats.dropped_levels;
  }
  if (counts[0].triangles == 0) throw core::Error(core::Status::Internal, "encodeBlock: Draco left level 0 empty");

  rec.lod_count = static_cast<uint32_t>(levels.size());
  for (uint32_t k = 0; k < graph::kMaxBlockLods; ++k) {
    const bool has = k < rec.lod_count;
    rec.triangles[k] = has ? counts[k].triangles : 0;
    rec.vertices[k] = has ? counts[k].vertices : 0;
    rec.error_m[k] = has ? static_cast<float>(levels[k].error_m) : 0.f;
    if (!has) continue;
    stats.triangles[k] += rec.triangles[k];
    stats.vertices[k] += rec.vertices[k];
    ++stats.blocks[k];
    stats.sloppy_levels += levels[k].method == LodMethod::Sloppy;
    stats.unlocked_levels += levels[k].method == LodMethod::SimplifyUnlocked;
    stats.max_error_m = std::max(stats.max_error_m, levels[k].error_m);
  }
  rec.triangle_count = rec.triangles[0];
  rec.vertex_count = rec.vertices[0];
  return bytes;
}

}  // namespace blvd::bake
