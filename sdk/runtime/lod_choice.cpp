// Level of detail per local block (DrawList::chooseLevels): Marvie's budget
// share when a frame-time target is set, else the coarsest level within
// lod_error_px on screen. Either way a block is seen only where it lies in a
// camera's frustum: a long block beside the street is measured from its
// nearest point in view, not from the street where the car is.
#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "core/math.h"
#include "runtime/draw_list.h"

namespace blvd::runtime {
namespace {

// A block's box: its centre relative to `eye`, and its half extents.
void blockBox(const graph::BlockRecord& r, const glm::dvec3& eye, glm::dvec3& center, glm::dvec3& half) {
  const glm::dvec3 lo(r.bbox_min[0], r.bbox_min[1], r.bbox_min[2]), hi(r.bbox_max[0], r.bbox_max[1], r.bbox_max[2]);
  center = (lo + hi) * 0.5 - eye;
  half = (hi - lo) * 0.5;
}

}  // namespace

void DrawList::setCameras(const render::Camera* cams, uint32_t n_cams) {
  n_cams_ = std::min(n_cams, kMaxViews);
  for (uint32_t v = 0; v < n_cams_; ++v) {
    const render::Camera& c = cams[v];
    frusta_[v] = render::Frustum::fromClip(render::viewProjectionRelative(c));
    eyes_[v] = render::enuToGltf(c.eye_enu);
    focal_px_[v] = c.height * 0.5 / std::tan(c.fov_y_deg * 0.5 * core::kDegToRad);
  }
}

// No frame budget: the coarsest level whose simplification error stays
// within lod_error_px on screen at the block's nearest point in any view
// (focal length over that distance: pixels per metre there). A block no
// view sees takes its coarsest level and counts no triangles.
void DrawList::levelsByError(const CellSlot& slot) {
  for (size_t i = 0; i < slot.blocks.size(); ++i) {
    const graph::BlockRecord& r = slot.blocks[i].record;
    const uint32_t levels = slot.blocks[i].levels;
    double px_per_m = 0;
    for (uint32_t v = 0; v < n_cams_; ++v) {
      glm::dvec3 center, half;
      blockBox(r, eyes_[v], center, half);
      const double dist = frusta_[v].nearestInside(center, half);
      if (dist < render::Frustum::kOutside) px_per_m = std::max(px_per_m, focal_px_[v] / std::max(dist, 1e-3));
    }
    uint8_t level = static_cast<uint8_t>(levels ? levels - 1 : 0);
    if (px_per_m > 0) {
      level = 0;
      for (uint32_t k = levels; k-- > 1;)
        if (r.error_m[k] * px_per_m <= lod_error_px_) {
          level = static_cast<uint8_t>(k);
          break;
        }
      block_tris_ += r.triangles[level];
    }
    level_[i] = level;
  }
}

// Marvie et al.: frustum-cull, renormalise the cell's coverage hints over
// the visible blocks (those any view's frustum holds), and share the polygon
// budget P_i = ACH_i · P.
void DrawList::chooseLevels(const CellSlot& slot, const stream::FrameBudget* budget) {
  block_tris_ = 0;
  if (!budget) return levelsByError(slot);
  floor_tris_ = 0;
  size_t nv = 0;
  for (size_t i = 0; i < slot.blocks.size(); ++i) {
    const graph::BlockRecord& r = slot.blocks[i].record;
    level_[i] = static_cast<uint8_t>(slot.blocks[i].levels ? slot.blocks[i].levels - 1 : 0);  // culled anyway
    bool seen = false;
    for (uint32_t v = 0; v < n_cams_ && !seen; ++v) {
      glm::dvec3 center, half;
      blockBox(r, eyes_[v], center, half);
      seen = frusta_[v].intersectsBox(center, half);
    }
    if (!seen) continue;
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
