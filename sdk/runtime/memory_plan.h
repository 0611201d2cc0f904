// The runtime's memory plan: every pool's size, worked out from the
// package's tables and the descriptor before anything is allocated, so that
// blvd_memory_required() and blvd_runtime_create() agree to the byte.
//
// Pools:
//   GPU   one slab per resident-cell slot, sized for the package's largest
//         cell in each dimension (vertex bytes, index bytes, meshes, impostor
//         atlas height): the current cell's local blocks and its impostors,
//         whose images share one atlas texture (render/slab_atlas.h), so a
//         slot's texels follow the bake's texel budget a cell, not the
//         number of layers or runs times the largest image. The atlas is
//         RGBA8 or, with blvd_runtime_desc.impostor_texture, ETC2.
//   CPU   staging: kStagingSlots arenas the loader thread decodes a cell into
//         (the render thread copies them to a slab), each for the largest cell;
//         tables: the package's graph, cell and block tables the runtime holds;
//         tracking: the tracker's ring, filter and matcher.
#pragma once
#include <cstdint>
#include <string>

#include "blvd/blvd.h"
#include "runtime/cell_loader.h"
#include "runtime/impostor_atlas.h"
#include "runtime/terrain_set.h"
#include "render/renderer.h"
#include "stream/city.h"

namespace blvd::runtime {

// What one cell needs resident: every level of each local block and every
// impostor layer, with the exact vertex and triangle counts the BLCK and IMPO
// records promise (the decoder checks them).
struct CellNeed {
  uint64_t vertex_bytes = 0, index_bytes = 0;
  uint64_t staging_bytes = 0;  // render::preparedBytes summed over the meshes
  uint32_t meshes = 0, textures = 0;
  uint16_t texture_width = 0, texture_height = 0;  // the largest impostor texture's
  int atlas_height = 0;  // the impostor images packed into an atlas `atlas_width` wide (-1: one is wider)
};
// `layers` and `atlas`: scratch of at least city.maxCellLayers() entries.
// An ETC2 atlas packs on its grid, and staging holds each image's ETC2 levels.
CellNeed cellNeed(const stream::City& city, uint32_t cell, int atlas_width, stream::LayerInfo* layers,
                  ImpostorAtlas& atlas, render::AtlasFormat format = render::AtlasFormat::Rgba8);

struct MemoryPlan {
  uint32_t resident_cells = 0;
  render::SlabDesc slab;           // one per resident cell
  uint64_t staging_arena_bytes = 0;  // per staging slot
  uint32_t staging_meshes = 0;       // per staging slot
  uint32_t max_cell_layers = 0;      // impostor layers of the cell with the most
  uint64_t staging_bytes = 0;        // all staging slots with their mesh tables
  uint64_t table_bytes = 0;          // the package tables held in memory
  uint64_t tracking_bytes = 0;       // tracker rings, filter, matcher
  TerrainPlan terrain;               // the terrain's tile slots and scratch (none without TERR)
  uint64_t cpu_bytes = 0;            // staging + tables + tracking + terrain scratch
  uint64_t gpu_bytes = 0;            // slabs, the terrain's with them
  uint32_t largest_cell = 0;         // the cell that needs the most bytes
  uint32_t max_local_blocks = 0;     // most local blocks of one cell (LOD scratch size)
};

// Bytes of one staging slot's table of prepared meshes.
uint64_t stagingTableBytes(uint32_t meshes);

// Plans for `desc` (defaults already applied) and `city`.
MemoryPlan planMemory(const blvd_runtime_desc& desc, const stream::City& city);

// "package needs 38.2 MiB for 3 resident cells, budget is 16 MiB" when the
// plan exceeds a budget of `desc`; empty when it fits.
std::string budgetError(const blvd_runtime_desc& desc, const MemoryPlan& plan);

}  // namespace blvd::runtime
