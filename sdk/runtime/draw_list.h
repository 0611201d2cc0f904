// A frame's draw list: what the renderer draws for the current cell in the
// current mode, and the object id of each entry (blvd_read_items).
//   BLVD / SINGLE / LOCAL: the resident cell's local blocks, each at the level
//     of detail the frame budget or the error bound gives it (lod_choice.cpp),
//     plus (not LOCAL) the impostor layers of the run that holds the viewer's
//     arc length (docs/decisions/0010).
//   FULL / RADIUS: reference modes for benchmarks, every block (or those
//     within a radius) at full detail, uploaded on first use outside the
//     memory budget (docs/decisions/0006).
// Vectors are reserved at create: building a list allocates nothing.
#pragma once
#include <cstdint>
#include <vector>

#include "blvd/blvd.h"
#include "render/camera.h"
#include "render/frustum.h"
#include "render/renderer.h"
#include "runtime/cell_slots.h"
#include "stream/city.h"
#include "stream/frame_budget.h"

namespace blvd::runtime {

class DrawList {
 public:
  // `lod_error_px`: the screen-space error bound when there is no frame budget.
  DrawList(const stream::City& city, const MemoryPlan& plan, float lod_error_px);

  static constexpr uint32_t kMaxViews = 16;

  // Builds this frame's list for `cell` at `arc_m` (kNone: nothing local),
  // seen by `n_cams` cameras (1..kMaxViews: the frame's, or each view's; the
  // first places the radius of RADIUS). A cell not resident yet draws the
  // last cell drawn, if it still is, and the frame is degraded. `budget` may
  // be null.
  void build(blvd_render_mode mode, float radius_m, uint32_t cell, double arc_m, const render::Camera* cams,
             uint32_t n_cams, const CellSlots& slots, const stream::FrameBudget* budget);
  // Every block uploaded once for the reference modes; throws core::Error.
  void ensureReferenceBlocks(render::Renderer& renderer);
  void releaseReferenceBlocks(render::Renderer& renderer);

  const render::MeshHandle* meshes() const { return draw_.data(); }
  const uint32_t* items() const { return draw_items_.data(); }
  size_t size() const { return draw_.size(); }
  uint32_t impostors() const { return impostors_; }
  uint32_t blocks() const { return uint32_t(draw_.size()) - impostors_ - terrain_; }
  // The terrain's tiles (runtime/terrain_set.h), after the rest, object id 0,
  // drawn behind the rest (RenderOptions::behind_from).
  void addTerrain(const render::MeshHandle* tiles, uint32_t n);
  uint32_t terrainTiles() const { return terrain_; }
  size_t behindFrom() const { return terrain_ ? draw_.size() - terrain_ : SIZE_MAX; }
  bool degraded() const { return degraded_; }
  void clear();  // nothing to draw (the sky and ground remain)
  uint32_t lastDrawnCell() const { return last_drawn_cell_; }
  uint64_t misses() const { return misses_; }
  // The local blocks' triangles at their chosen levels, and at their
  // coarsest levels (what the budget cannot go under), last frame.
  uint64_t blockTriangles() const { return block_tris_; }
  uint64_t floorTriangles() const { return floor_tris_; }

  // The start of the run that holds arc length `arc_m` (the last run starting
  // at or before it; the first when the list is empty or arc_m is before all).
  static float activeRun(const stream::LayerInfo* layers, size_t count, double arc_m);

 private:
  void addBlock(uint32_t b);
  void addRadius(float radius_m, const render::Camera& cam);
  void addCell(blvd_render_mode mode, const CellSlot& slot, uint32_t cell, double arc_m);
  // lod_choice.cpp: a level per block of `slot` into level_, for the
  // cameras whose frusta setCameras() took.
  void setCameras(const render::Camera* cams, uint32_t n_cams);
  void chooseLevels(const CellSlot& slot, const stream::FrameBudget* budget);
  void levelsByError(const CellSlot& slot);

  const stream::City& city_;
  float lod_error_px_;
  std::vector<render::MeshHandle> reference_blocks_;
  struct Box {
    float lo[2], hi[2];  // glTF x and z of a block's box
  };
  std::vector<Box> reference_boxes_;  // with reference_blocks_
  std::vector<render::MeshHandle> draw_;
  std::vector<uint32_t> draw_items_;
  uint32_t impostors_ = 0, terrain_ = 0;
  uint32_t last_drawn_cell_ = graph::kNone;
  bool degraded_ = false;
  uint64_t misses_ = 0;
  uint64_t block_tris_ = 0, floor_tris_ = 0;
  // The frame's cameras: their frusta (eye-relative) and focal lengths.
  render::Frustum frusta_[kMaxViews];
  glm::dvec3 eyes_[kMaxViews];
  double focal_px_[kMaxViews] = {};
  uint32_t n_cams_ = 0;
  // chooseLevels scratch, sized for the largest cell at create.
  std::vector<float> ach_;
  std::vector<stream::LodChain> chains_;
  std::vector<uint32_t> order_, visible_;
  std::vector<uint8_t> level_, visible_level_;
};

}  // namespace blvd::runtime
