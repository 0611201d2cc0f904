#include "runtime/draw_list.h"

#include <algorithm>

#include "core/status.h"

namespace blvd::runtime {

DrawList::DrawList(const stream::City& city, const MemoryPlan& plan, float lod_error_px)
    : city_(city), lod_error_px_(lod_error_px) {
  draw_.reserve(plan.slab.meshes + 1 + plan.terrain.slots);  // the reference modes reserve for every block when first chosen
  draw_items_.reserve(draw_.capacity());
  const size_t nb = plan.max_local_blocks;
  ach_.resize(nb);
  chains_.resize(nb);
  order_.resize(nb);
  visible_.resize(nb);
  level_.resize(nb);
  visible_level_.resize(nb);
}

void DrawList::ensureReferenceBlocks(render::Renderer& renderer) {
  if (!reference_blocks_.empty()) return;
  geo::MeshData mesh;
  std::string err;
  const uint32_t n = city_.blockCount();
  if (!renderer.reserveMeshes(n)) throw core::Error(core::Status::Internal, renderer.lastError());
  draw_.reserve(draw_.capacity() + n);
  draw_items_.reserve(draw_.capacity());
  reference_blocks_.resize(n);
  reference_boxes_.resize(n);
  for (uint32_t b = 0; b < n; ++b) {
    const graph::BlockRecord r = city_.block(b);
    reference_boxes_[b] = Box{{r.bbox_min[0], r.bbox_min[2]}, {r.bbox_max[0], r.bbox_max[2]}};
    const core::Status st = city_.decodeBlock(b, mesh, err);
    if (st != core::Status::Ok) throw core::Error(st, err);
    if (mesh.empty()) continue;
    reference_blocks_[b] = renderer.upload(mesh);
    if (reference_blocks_[b].id == 0)
      throw core::Error(core::Status::Internal, "block " + std::to_string(b) + ": " + renderer.lastError());
  }
}

void DrawList::releaseReferenceBlocks(render::Renderer& renderer) {
  for (render::MeshHandle h : reference_blocks_) renderer.release(h);
  reference_blocks_.clear();
  reference_boxes_.clear();
}

float DrawList::activeRun(const stream::LayerInfo* layers, size_t count, double arc_m) {
  float run = count == 0 ? 0.f : layers[0].run_from_m;
  for (size_t i = 0; i < count; ++i)
    if (double(layers[i].run_from_m) <= arc_m) run = layers[i].run_from_m;
  return run;
}

void DrawList::addBlock(uint32_t b) {
  if (b < reference_blocks_.size() && reference_blocks_[b].id) {
    draw_.push_back(reference_blocks_[b]);
    draw_items_.push_back(b + 1);
  }
}

// Visibility radius (the VOP baseline): blocks whose box comes within R.
void DrawList::addRadius(float radius_m, const render::Camera& cam) {
  const double ex = cam.eye_enu.x, ez = -cam.eye_enu.y;
  for (uint32_t b = 0; b < reference_boxes_.size(); ++b) {
    const Box& r = reference_boxes_[b];
    const double dx = std::max({double(r.lo[0]) - ex, 0.0, ex - double(r.hi[0])});
    const double dz = std::max({double(r.lo[1]) - ez, 0.0, ez - double(r.hi[1])});
    if (dx * dx + dz * dz <= double(radius_m) * radius_m) addBlock(b);
  }
}

// Sillion 97 §3.1: the local model as geometry, each block at the level of
// detail chosen for it, plus the cell's impostors for the rest; the blocks
// they stand for are never drawn with them (K06 §3.1.2): they are not local.
// A long or bending cell has a set per run: the viewer's run's.
void DrawList::addCell(blvd_render_mode mode, const CellSlot& slot, uint32_t cell, double arc_m) {
  for (size_t i = 0; i < slot.blocks.size(); ++i) {
    draw_.push_back(slot.blocks[i].lod[level_[i]]);
    draw_items_.push_back(slot.blocks[i].block + 1);
  }
  if (mode == BLVD_MODE_LOCAL) return;
  const bool single = mode == BLVD_MODE_SINGLE;
  const auto& handles = single ? slot.single : slot.layered;
  const stream::LayerInfo* layers = slot.layers.data() + (single ? slot.layered_count : 0);
  const size_t count = single ? slot.single_count : slot.layered_count;
  const float run = activeRun(layers, count, slot.cell == cell ? arc_m : 0.0);
  for (size_t i = 0; i < handles.size() && i < count; ++i) {
    if (layers[i].run_from_m != run) continue;
    draw_.push_back(handles[i]);
    draw_items_.push_back(BLVD_ITEM_IMPOSTOR | uint32_t(i + 1));
    ++impostors_;
  }
}

void DrawList::addTerrain(const render::MeshHandle* tiles, uint32_t n) {
  for (uint32_t i = 0; i < n; ++i) {
    draw_.push_back(tiles[i]);
    draw_items_.push_back(0);
  }
  terrain_ += n;
}

void DrawList::clear() {
  draw_.clear();
  draw_items_.clear();
  impostors_ = terrain_ = 0;
  degraded_ = false;
}

void DrawList::build(blvd_render_mode mode, float radius_m, uint32_t cell, double arc_m, const render::Camera* cams,
                     uint32_t n_cams, const CellSlots& slots, const stream::FrameBudget* budget) {
  clear();
  if (mode == BLVD_MODE_FULL) {
    for (uint32_t b = 0; b < reference_blocks_.size(); ++b) addBlock(b);
    return;
  }
  if (mode == BLVD_MODE_RADIUS) return addRadius(radius_m, cams[0]);
  if (cell == graph::kNone) return;
  const CellSlot* slot = slots.resident(cell);
  if (!slot) {
    // Not resident yet: never wait; draw the last cell drawn if it still is, and say so.
    degraded_ = true;
    ++misses_;
    slot = slots.resident(last_drawn_cell_);
    if (!slot) return;
  }
  last_drawn_cell_ = slot->cell;
  setCameras(cams, n_cams);
  chooseLevels(*slot, budget);
  addCell(mode, *slot, cell, arc_m);
}

}  // namespace blvd::runtime
