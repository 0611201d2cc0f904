// View-frustum culling of axis-aligned boxes (Gribb & Hartmann 2001, plane
// extraction from the clip matrix). Works on eye-relative coordinates so the
// test stays exact far from the package origin.
#pragma once
#include <cmath>
#include <glm/glm.hpp>

namespace blvd::render {

struct Frustum {
  glm::dvec4 planes[6];  // (n, d): inside when dot(n, p) + d >= 0
  double near_reach = 0;  // the eye's distance to the near rectangle's corners

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

  // The distance from the eye (the origin) to the nearest point of the box
  // that lies inside the frustum; kOutside when none does. A box reaching
  // within near_reach of the eye gives its own nearest distance (it may hold
  // part of the near plane, where nothing nearer can be seen anyway).
  static constexpr double kOutside = 1e300;
  double nearestInside(const glm::dvec3& center, const glm::dvec3& half_extent) const;
};

}  // namespace blvd::render
