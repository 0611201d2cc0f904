// Points along a cell's street polyline, and the eye height and view
// distance of the bake's item buffers and captures.
#pragma once
#include <algorithm>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "graph/street_graph.h"

namespace blvd::bake {

constexpr double kEyeHeight = 1.5;  // metres above the street

// The eye kEyeHeight above the ground at street point p (flat ground: 0).
template <class Ground>
glm::dvec3 eyeAt(glm::dvec2 p, const Ground& ground) {
  return {p.x, p.y, (ground ? ground(p) : 0.0) + kEyeHeight};
}
constexpr double kViewDistanceM = 6000.0;  // far plane of every item buffer and capture

// The point at arc length `s` along half-edge `e` (clamped to its ends).
inline glm::dvec2 pointAt(const graph::StreetGraph& g, const graph::HalfEdge& e, double s) {
  const glm::dvec2* p = &g.points[e.pts_begin];
  for (uint32_t i = 1; i < e.pts_count; ++i) {
    const double l = glm::length(p[i] - p[i - 1]);
    if (s <= l || i + 1 == e.pts_count) return l > 0 ? p[i - 1] + (p[i] - p[i - 1]) * std::min(1.0, s / l) : p[i];
    s -= l;
  }
  return p[e.pts_count - 1];
}

}  // namespace blvd::bake
