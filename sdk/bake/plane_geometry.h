// Distances between points and segments in the plane, for the bake's
// geometry (the depth mesh's contours, wall merging, local models).
#pragma once
#include <algorithm>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

namespace blvd::bake {

// Distance from p to segment ab; *t (if given) gets the nearest point's
// parameter along ab, in [0, 1]. A degenerate segment is its point a.
inline double pointSegmentDistance(glm::dvec2 p, glm::dvec2 a, glm::dvec2 b, double* t = nullptr) {
  const glm::dvec2 ab = b - a;
  const double len2 = glm::dot(ab, ab);
  const double s = len2 > 0.0 ? std::clamp(glm::dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
  if (t) *t = s;
  return glm::length(p - (a + ab * s));
}

// Distance between segments pq and ab: 0 when they cross.
inline double segmentDistance(glm::dvec2 p, glm::dvec2 q, glm::dvec2 a, glm::dvec2 b) {
  auto cross = [](glm::dvec2 u, glm::dvec2 v) { return u.x * v.y - u.y * v.x; };
  const double d1 = cross(q - p, a - p), d2 = cross(q - p, b - p);
  const double d3 = cross(b - a, p - a), d4 = cross(b - a, q - a);
  if (d1 * d2 < 0.0 && d3 * d4 < 0.0) return 0.0;
  return std::min({pointSegmentDistance(p, a, b), pointSegmentDistance(q, a, b), pointSegmentDistance(a, p, q),
                   pointSegmentDistance(b, p, q)});
}

}  // namespace blvd::bake
