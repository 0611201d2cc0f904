// The terrain beyond the blocks (a package's TERR tiles), streamed into a
// fixed set of GPU slots and chosen each frame by screen-space error, as
// chunked LOD does (Ulrich 2002; the error as 3D Tiles' geometricError over
// the distance, in display pixels):
//
//   choose  from the root, the leaf of most screen-space error above
//           `error_px` is split into its four children, while the tree chosen
//           fits the slots (a rooted tree: every tile's parent is in it);
//   load    up to kLoadsPerFrame tiles of the tree not resident, coarse
//           first, into a free slot or the deepest resident tile outside the
//           tree (so that a resident tile's parent always is too);
//   draw    from the root down through the tree, a tile's children when all
//           four are resident, else the tile itself.
//
// A tile's mesh: its grid at the heights the bake stored, two triangles a
// square (split as the bake measured its error), with skirts hanging from
// its inner edges (not the root's outline) deep enough to close any crack
// between levels: its level's error plus twice the root's (a neighbour's
// error is at most the root's) plus a metre. Its colour is the look's
// ground. The runtime draws the tiles behind the city (the far part of the
// depth range, RenderOptions::behind_from): they show only where no block or
// impostor drew, so the city's draped ground never fights them and they need
// not be lowered under it.
//
// Memory: slots, scratch and the mesh pool entries are made at create
// (plan()); a frame allocates nothing. A tile that fails to load is
// counted and not asked for again; one whose bytes a package on a server has
// not brought yet is asked for again (uncachedBlobs()).
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "geo/mesh.h"
#include "render/camera.h"
#include "render/renderer.h"
#include "stream/city.h"

namespace blvd::runtime {

struct TerrainPlan {
  uint32_t slots = 0;  // 0: the package has no terrain
  render::SlabDesc slab;  // one per slot
  uint64_t gpu_bytes = 0, cpu_bytes = 0;
};

class TerrainSet {
 public:
  static constexpr uint32_t kMaxSlots = 64;
  static constexpr uint32_t kLoadsPerFrame = 4;

  static TerrainPlan plan(const stream::City& city);

  // Creates the plan's slabs. Throws core::Error (NoMem when the GL cannot
  // back them, Internal otherwise).
  TerrainSet(const stream::City& city, render::Renderer& renderer, const TerrainPlan& plan, float error_px);

  // Chooses, loads and lists this frame's tiles for `cam`; `out` receives at
  // most slots() handles. Returns their count.
  uint32_t frame(const render::Camera& cam, render::MeshHandle* out);
  // Chooses the tree for `cam` and loads every tile of it that is missing
  // (blvd_wait_resident: a first frame that shows the terrain settled).
  void settle(const render::Camera& cam);

  uint32_t slots() const { return plan_.slots; }
  uint64_t loads() const { return loads_; }
  uint64_t loadErrors() const { return load_errors_; }
  const std::string& lastError() const { return last_error_; }
  // The tiles of the tree chosen last frame (draw() may show coarser ones
  // where children are not resident yet).
  uint32_t chosen() const { return chosen_; }
  // The blobs of the tiles last frame wanted and could not load because a
  // package on a server has not brought them yet (not errors: asked for
  // again each frame; the link prefetch fetches them). At most slots().
  const std::vector<uint32_t>& uncachedBlobs() const { return uncached_; }

  // The mesh of tile `tile` (heights[grid²]) as drawn: exposed for
  // the crack tests, which draw chosen levels side by side. `skirts` false
  // leaves them out (to show that the tests see cracks without them).
  static void tileMesh(const graph::TerrainLayout& l, uint32_t tile, const float* heights, const uint8_t rgba[4],
                       bool skirts, geo::MeshData& out);

 private:
  double screenError(uint32_t tile, const render::Camera& cam);
  void choose(const render::Camera& cam);
  void loadMissing(uint32_t max_loads);
  core::Status load(uint32_t tile, uint32_t slot);
  uint32_t victim() const;
  uint32_t residentSlot(uint32_t tile) const;
  bool inTree(uint32_t tile) const;
  uint32_t draw(render::MeshHandle* out);

  const stream::City& city_;
  render::Renderer& renderer_;
  TerrainPlan plan_;
  float error_px_;
  graph::TerrainLayout layout_;
  uint8_t colour_[4] = {0, 0, 0, 255};
  // Slots.
  std::vector<render::SlabHandle> slab_;
  std::vector<render::MeshHandle> mesh_;
  std::vector<uint32_t> tile_;     // the tile a slot holds, or kNoTile
  std::vector<uint64_t> used_;     // the frame it was last in the tree
  // The tree chosen this frame: tiles, their errors in pixels, and the index
  // of each internal node's first child (children are consecutive).
  std::vector<uint32_t> tree_;
  std::vector<double> tree_px_;
  std::vector<uint32_t> first_child_;
  std::vector<uint32_t> stack_;
  uint32_t chosen_ = 0;
  std::vector<uint32_t> failed_;   // tiles that failed to load
  std::vector<uint32_t> uncached_; // blobs of tiles not over the link yet
  // Load scratch, reserved at create.
  std::vector<float> heights_;
  std::vector<uint8_t> blob_;
  geo::MeshData mesh_data_;
  std::vector<uint8_t> arena_bytes_;
  uint64_t tick_ = 0, loads_ = 0, load_errors_ = 0;
  std::string last_error_;
};

}  // namespace blvd::runtime
