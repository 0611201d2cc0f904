// Level of detail per local block (DrawList::chooseLevels): Marvie's budget
// share when a frame-time target is set, else the coarsest level within
// lod_error_px on screen.
#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "core/math.h"
#include "render/frustum.h"
#include "runtime/draw_list.h"

namespace blvd::runtime {

// No frame budget: the coarsest level whose simplification error stays
// within lod_error_px on screen at the block box's nearest point.
void DrawList::levelsByError(const CellSlot& slot, const render::Camera& cam) {
  const glm::dvec3 eye = render::enuToGltf(cam.eye_enu);
  const double focal_px = cam.height * 0.5 / std::tan(cam.fov_y_deg * 0.5 * core::kDegToRad);
  for (size_t i = 0; i < slot.blocks.size(); ++i) {
    const graph::BlockRecord& r = slot.blocks[i].record;
    const glm::dvec3 lo(r.bbox_min[0], r.bbox_min[1], r.bbox_min[2]), hi(r.bbox_max[0], r.bbox_max[1], r.bbox_max[2]);
    const double dist = std::max(glm::length(glm::max(glm::max(lo - eye, eye - hi), glm::dvec3(0.0))), 1e-3);
    uint8_t level = 0;
    for (uint32_t k = slot.blocks[i].levels; k-- > 1;)
      if (r.error_m[k] * focal_px <= lod_error_px_ * dist) {
        level = static_cast<uint8_t>(k);
        break;
      }
    level_[i] = level;
    block_tris_ += r.triangles[level];
  }
}

// Marvie et al.: frustum-cull, renormalise the cell's coverage hints over
// the visible blocks, and share the polygon budget P_i = ACH_i · P.
void DrawList::chooseLevels(const CellSlot& slot, const render::Camera& cam, const stream::FrameBudget* budget) {
  block_tris_ = 0;
  if (!budget) return levelsByError(slot, cam);
  floor_tris_ = 0;
  const glm::dvec3 eye = render::enuToGltf(cam.eye_enu);
  const render::Frustum frustum = render::Frustum::fromClip(render::viewProjectionRelative(cam));
  size_t nv = 0;
  for (size_t i = 0; i < slot.blocks.size(); ++i) {
    const graph::BlockRecord& r = slot.blocks[i].record;
    const glm::dvec3 lo(r.bbox_min[0], r.bbox_min[1], r.bbox_min[2]), hi(r.bbox_max[0], r.bbox_max[1], r.bbox_max[2]);
    level_[i] = static_cast<uint8_t>(slot.blocks[i].levels ? slot.blocks[i].levels - 1 : 0);  // culled anyway
    if (!frustum.intersectsBox((lo + hi) * 0.5 - eye, (hi - lo) * 0.5)) continue;
    visible_[nv] = static_cast<uint32_t>(i);
    ach_[nv] = slot.blocks[i].ach;
    chains_[nv] = stream::LodChain{r.triangles, slot.blocks[i].levels};
    ++nv;
    if (slot.blocks[i].levels) floor_tris_ += r.triangles[slot.blocks[i].levels - 1];
  }
  block_tris_ = stream::shareBudget(budget->polygonBudget(), ach_.data(), chains_.data(), nv, order_.data(),
                                    visible_level_.data());
  for (size_t j = 0; j < nv; ++j) level_[visible_[j]] = visible_level_[j];
}

}  // namespace blvd::runtime
