// One block's package entry: its GLB (every level of detail, MSFT_lod) and the
// BLCK record fields that describe it, so the runtime plans pools and picks a
// level from the record alone.
#pragma once
#include <cstdint>
#include <vector>

#include "bake/lod_chain.h"
#include "geo/mesh.h"
#include "graph/block_table.h"
#include "package/glb.h"

namespace blvd::bake {

// Running totals for the bake summary, META and report.
struct LodStats {
  uint64_t triangles[graph::kMaxBlockLods] = {0, 0, 0, 0};  // summed over blocks having the level
  uint64_t vertices[graph::kMaxBlockLods] = {0, 0, 0, 0};
  uint64_t blocks[graph::kMaxBlockLods] = {0, 0, 0, 0};     // blocks having the level
  uint64_t sloppy_levels = 0;   // levels meshopt_simplify could not reach (meshopt_simplifySloppy made them)
  uint64_t unlocked_levels = 0; // levels that needed the border unlocked
  uint64_t dropped_levels = 0;  // levels Draco left without fewer triangles than the level before
  double max_error_m = 0;
  double seconds = 0;           // simplification (the encoding is counted with the GLBs)
};

// Builds `mesh`'s LOD chain, encodes it and fills `rec`'s bounds, lod_count,
// triangles, vertices, error_m, triangle_count and vertex_count (the counts
// come from the encoder, so they are what decoding gives). `mesh` must not be
// empty. Throws as encodeGlbLevels does.
std::vector<uint8_t> encodeBlock(const geo::MeshData& mesh, const LodOptions& lod, const package::GlbOptions& glb,
                                 graph::BlockRecord& rec, LodStats& stats);

}  // namespace blvd::bake
