#include "cli/route.h"

#include <algorithm>
#include <cmath>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

namespace blvd::cli {

std::vector<Pose> samplePoses(const graph::GraphSource& g, const std::vector<uint32_t>& route, double step_m,
                              double look_ahead_m, double lateral_m) {
  // Flatten the route into one polyline with the cell of each point.
  std::vector<glm::dvec2> pts;
  std::vector<uint32_t> cell_of;
  std::vector<double> arc;
  for (uint32_t h : route) {
    const graph::HalfEdge e = g.halfedge(h);
    for (uint32_t i = pts.empty() ? 0 : 1; i < e.pts_count; ++i) {
      const glm::dvec2 p = g.point(e.pts_begin + i);
      arc.push_back(pts.empty() ? 0 : arc.back() + glm::length(p - pts.back()));
      pts.push_back(p);
      cell_of.push_back(h);
    }
  }
  std::vector<Pose> poses;
  if (pts.size() < 2 || step_m <= 0) return poses;
  auto at = [&](double s, uint32_t* cell) {
    s = glm::clamp(s, 0.0, arc.back());
    size_t i = std::upper_bound(arc.begin(), arc.end(), s) - arc.begin();
    i = glm::clamp<size_t>(i, 1, pts.size() - 1);
    const double seg = arc[i] - arc[i - 1];
    const double t = seg > 0 ? (s - arc[i - 1]) / seg : 0;
    if (cell) *cell = cell_of[i];
    return pts[i - 1] + (pts[i] - pts[i - 1]) * t;
  };
  for (double s = 0; s <= arc.back(); s += step_m) {
    Pose p;
    const glm::dvec2 here = at(s, &p.cell);
    glm::dvec2 ahead = at(s + look_ahead_m, nullptr) - here;
    if (glm::length(ahead) < 1e-6) ahead = here - at(s - look_ahead_m, nullptr);
    const glm::dvec2 d = glm::length(ahead) > 0 ? glm::normalize(ahead) : glm::dvec2(0, 1);
    const glm::dvec2 right(d.y, -d.x);
    p.x = here.x + right.x * lateral_m;
    p.y = here.y + right.y * lateral_m;
    p.heading_deg = std::fmod(glm::degrees(std::atan2(d.x, d.y)) + 360.0, 360.0);
    poses.push_back(p);
  }
  return poses;
}

std::vector<Pose> visitPoses(const graph::GraphSource& g, const std::vector<uint32_t>& route) {
  const std::vector<Pose> all = samplePoses(g, route, 1.0);
  std::vector<Pose> poses;
  for (size_t a = 0; a < all.size();) {
    size_t b = a;
    while (b < all.size() && all[b].cell == all[a].cell) ++b;
    poses.push_back(all[a + (b - a) / 2]);
    a = b;
  }
  return poses;
}

}  // namespace blvd::cli
