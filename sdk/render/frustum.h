// View-frustum culling of axis-aligned boxes (Gribb & Hartmann 2001, plane
// extraction from the clip matrix). Works on eye-relative coordinates so the
// test stays exact far from the package origin.
#pragma once
#include <cmath>
#include <glm/glm.hpp>

namespace blvd::render {

struct Frustum {
  glm::dvec4 planes[6];  // (n, d): inside when dot(n, p) + d >= 0

  // From projection * view for eye-relative positions.
  static Frustum fromClip(const glm::dmat4& clip);

  // False only when the box lies wholly outside one plane (conservative: a
  // box near a frustum corner may pass although invisible).
  bool intersectsBox(const glm::dvec3& center, const glm::dvec3& half_extent) const {
    for (const glm::dvec4& pl : planes) {
      const double r = half_extent.x * std::abs(pl.x) + half_extent.y * std::abs(pl.y) +
                       half_extent.z * std::abs(pl.z);
      if (pl.x * center.x + pl.y * center.y + pl.z * center.z + pl.w < -r) return false;
    }
    return true;
  }
};

}  // namespace blvd::render
