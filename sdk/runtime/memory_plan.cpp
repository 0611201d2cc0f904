#include "runtime/memory_plan.h"

#include <algorithm>
#include <cstdio>
#include <vector>

#include "render/atlas_etc2.h"
#include "runtime/cell_loader.h"
#include "core/status.h"
#include "track/tracker.h"

namespace blvd::runtime {
namespace {

// Index bytes of a mesh of v vertices and t triangles, plus the 4-byte
// alignment a slab placement may add.
uint64_t indexBytes(uint64_t v, uint64_t t) { return t * 3 * (v < 0xFFFF ? 2 : 4) + 3; }

void addMesh(CellNeed& n, uint64_t v, uint64_t t, int tw, int th, bool etc2 = false) {
  n.vertex_bytes += v * render::kVertexBytes;
  n.index_bytes += indexBytes(v, t);
  // An ETC2 atlas's levels follow in the arena, 16-byte aligned (StagingArena::take).
  n.staging_bytes += render::preparedBytes(v, t * 3, tw, th) + (etc2 ? render::atlasEtc2Bytes(tw, th) + 16 : 0);
  ++n.meshes;
  if (tw > 0) ++n.textures;
}

}  // namespace

CellNeed cellNeed(const stream::City& city, uint32_t cell, int atlas_width, stream::LayerInfo* layers,
                  ImpostorAtlas& atlas, render::AtlasFormat format) {
  const bool etc2 = format == render::AtlasFormat::Etc2;
  CellNeed n;
  for (const uint32_t b : city.streets().localBlocks(cell)) {
    const graph::BlockRecord r = city.block(b);
    for (uint32_t k = 0; k < r.lod_count; ++k)
      if (r.triangles[k]) addMesh(n, r.vertices[k], r.triangles[k], 0, 0);
  }
  uint32_t layered = 0, single = 0;
  city.cellLayers(cell, layers, city.maxCellLayers(), &layered, &single);
  for (uint32_t i = 0; i < layered + single; ++i) {
    const stream::LayerInfo& l = layers[i];
    addMesh(n, l.vertices, l.triangles, l.texture_width, l.texture_height, etc2);
    n.texture_width = std::max(n.texture_width, l.texture_width);
    n.texture_height = std::max(n.texture_height, l.texture_height);
  }
  if (n.textures) n.atlas_height = atlas.pack(layers, layered + single, atlas_width, render::atlasAlign(format));
  return n;
}

// The slab and staging from the header's pool sizing alone, for tables that
// come over the link a page at a time (reading every cell would fetch them
// all). A sum of the header's maxima bounds the most any one cell needs;
// textures' mip chains at most 4/3 of their level 0 plus, per layer, a row
// and a column of rounding (8 × (w + h) + 128 bytes); 64 bytes of alignment
// per mesh; an ETC2 atlas's levels at most 2/3 of a byte a texel of their
// place (32 × (w + h) + 1024 texels of rounding a layer). A cell past the
// header is refused by the loader's checks.
static void planFromHeader(const stream::City& city, MemoryPlan& p) {
  const package::PackageHeader& h = city.header();
  const uint64_t v = uint64_t(h.max_cell_local_vertices) + h.max_cell_impostor_vertices;
  const uint64_t t = uint64_t(h.max_cell_local_triangles) + h.max_cell_impostor_triangles;
  const uint32_t meshes = h.max_cell_local_blocks * graph::kMaxBlockLods + h.max_cell_impostor_layers;
  const uint64_t rounding = 8ull * (h.max_impostor_texture_width + h.max_impostor_texture_height) + 128;
  p.slab.vertex_bytes = v * render::kVertexBytes;
  p.slab.index_bytes = t * 3 * 4 + 3ull * meshes;
  p.slab.meshes = meshes;
  if (h.max_cell_impostor_layers)
    p.slab.atlas_height = impostorAtlasHeightBound(h, p.slab.atlas_width, p.slab.atlas_format);
  p.staging_arena_bytes = p.slab.vertex_bytes + t * 3 * 4 + h.max_cell_impostor_texture_bytes * 4 / 3 +
                          h.max_cell_impostor_layers * rounding + 64ull * meshes;
  if (p.slab.atlas_format == render::AtlasFormat::Etc2) {
    const uint64_t place_rounding = 32ull * (h.max_impostor_texture_width + h.max_impostor_texture_height) + 1024;
    p.staging_arena_bytes +=
        (h.max_cell_impostor_texture_bytes / 4 + h.max_cell_impostor_layers * place_rounding) * 2 / 3 + 16ull * meshes;
  }
  p.largest_cell = graph::kNone;
}

uint64_t stagingTableBytes(uint32_t meshes) { return uint64_t(meshes) * sizeof(StagedMesh); }

MemoryPlan planMemory(const blvd_runtime_desc& desc, const stream::City& city) {
  MemoryPlan p;
  p.resident_cells = desc.max_resident_cells;
  const int tw = city.header().max_impostor_texture_width, th = city.header().max_impostor_texture_height;
  p.max_local_blocks = city.header().max_cell_local_blocks;
  p.slab.atlas_format =
      desc.impostor_texture == BLVD_TEXTURE_ETC2 ? render::AtlasFormat::Etc2 : render::AtlasFormat::Rgba8;
  p.slab.atlas_width = impostorAtlasWidth(city.header(), p.slab.atlas_format);
  uint64_t most = 0;
  // The header's maxima size scratch arrays and slab textures: a package whose
  // tables exceed them is corrupt, not a reason to write past an array.
  auto corrupt = [&](const std::string& what) {
    throw core::Error(core::Status::Corrupt, city.package().name() + ": header pool sizing is below the tables: " + what);
  };
  std::vector<stream::LayerInfo> layers(city.maxCellLayers());
  ImpostorAtlas atlas;
  atlas.resize(layers.size());
  if (city.tablesOverLink()) planFromHeader(city, p);
  for (uint32_t c = 0; !city.tablesOverLink() && c < city.streets().cellCount(); ++c) {
    if (city.streets().localBlocks(c).size() > p.max_local_blocks)
      corrupt("cell " + std::to_string(c) + " has more local blocks than the header says");
    const CellNeed n = cellNeed(city, c, p.slab.atlas_width, layers.data(), atlas, p.slab.atlas_format);
    if (n.texture_width > tw || n.texture_height > th || n.atlas_height < 0)
      corrupt("cell " + std::to_string(c) + " has an impostor texture larger than the header says");
    p.slab.vertex_bytes = std::max(p.slab.vertex_bytes, n.vertex_bytes);
    p.slab.index_bytes = std::max(p.slab.index_bytes, n.index_bytes);
    p.slab.meshes = std::max(p.slab.meshes, n.meshes);
    p.slab.atlas_height = std::max(p.slab.atlas_height, n.atlas_height);
    p.staging_arena_bytes = std::max(p.staging_arena_bytes, n.staging_bytes);
    const uint64_t total = n.vertex_bytes + n.index_bytes + n.staging_bytes;
    if (total > most) most = total, p.largest_cell = c;
  }
  // A slab needs at least one of each so that an empty city still creates.
  p.slab.vertex_bytes = std::max<uint64_t>(p.slab.vertex_bytes, render::kVertexBytes);
  p.slab.index_bytes = std::max<uint64_t>(p.slab.index_bytes, 8);
  p.slab.meshes = std::max(p.slab.meshes, 1u);
  // A 3.3 header names the atlas the bake packed every cell into (5.1: on
  // the ETC2 grid too): the same slots whether the tables are read whole or
  // over the link a page at a time.
  const int packed = packedAtlasHeight(city.header(), p.slab.atlas_format);
  if (packed && !city.tablesOverLink()) {
    if (p.slab.atlas_height > packed) corrupt("a cell's impostor images take more of the atlas than the header says");
    p.slab.atlas_height = packed;
  }
  if (p.slab.atlas_height == 0) p.slab.atlas_width = 0;
  p.staging_meshes = p.slab.meshes;
  p.staging_bytes = kStagingSlots * (p.staging_arena_bytes + stagingTableBytes(p.staging_meshes));
  p.table_bytes = city.tableBytes();
  track::TrackerDesc td;
  td.ring_capacity = desc.ring_capacity;
  const track::Tracker probe(city.frame(), &city.streets(), td);
  p.max_cell_layers = city.maxCellLayers();
  p.tracking_bytes = probe.bytes();
  p.terrain = TerrainSet::plan(city);
  p.cpu_bytes = p.staging_bytes + p.table_bytes + p.tracking_bytes + p.terrain.cpu_bytes;
  p.gpu_bytes = uint64_t(p.resident_cells) * render::slabGpuBytes(p.slab) + p.terrain.gpu_bytes;
  return p;
}

std::string budgetError(const blvd_runtime_desc& desc, const MemoryPlan& p) {
  char buf[256];
  const double mib = 1024.0 * 1024.0;
  if (p.cpu_bytes > desc.memory_budget_bytes) {
    std::snprintf(buf, sizeof buf,
                  "package needs %.1f MiB for %u resident cells (staging %.1f, tables %.1f, tracking %.1f), "
                  "memory budget is %.1f MiB",
                  p.cpu_bytes / mib, p.resident_cells, p.staging_bytes / mib, p.table_bytes / mib,
                  p.tracking_bytes / mib, desc.memory_budget_bytes / mib);
    return buf;
  }
  if (p.gpu_bytes > desc.gpu_budget_bytes) {
    std::snprintf(buf, sizeof buf, "package needs %.1f MiB of GPU memory for %u resident cells, GPU budget is %.1f MiB",
                  p.gpu_bytes / mib, p.resident_cells, desc.gpu_budget_bytes / mib);
    return buf;
  }
  return {};
}

}  // namespace blvd::runtime
