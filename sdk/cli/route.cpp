#include "cli/route.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <unordered_map>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

namespace blvd::cli {

std::vector<uint32_t> autoRoute(const graph::StreetGraph& g, uint32_t cells, uint64_t seed) {
  std::vector<uint32_t> route;
  if (g.halfedges.empty() || cells == 0) return route;
  std::mt19937_64 rng(seed);
  std::vector<uint32_t> starts;
  for (uint32_t h = 0; h < g.halfedges.size(); ++h)
    if (g.halfedges[h].length >= 30 && g.halfedges[h].road_class <= graph::RoadClass::Residential &&
        !(g.halfedges[h].flags & graph::kTunnel) && g.successors.count(h) > 0)
      starts.push_back(h);
  if (starts.empty()) starts.push_back(0);
  // Straight on scores highest and seeded noise picks among turns. A cell
  // already driven is allowed again (a long route in a small city must loop)
  // but costs a penalty per earlier visit, and a U-turn only at a dead end.
  std::unordered_map<uint32_t, int> visits;
  std::vector<uint32_t> r{starts[rng() % starts.size()]};
  visits[r[0]] = 1;
  while (r.size() < cells) {
    const uint32_t h = r.back();
    const glm::dvec2 d = graph::cellDirection(g, h, true);
    uint32_t best = graph::kNone;
    double best_score = -1e9;
    for (const uint32_t* s = g.successors.begin(h); s != g.successors.end(h); ++s) {
      if (g.halfedges[*s].flags & graph::kTunnel) continue;
      const bool uturn = *s == g.halfedges[h].twin;
      const double score = glm::dot(d, graph::cellDirection(g, *s, false)) + 0.6 * std::uniform_real_distribution<>(0, 1)(rng) -
                           3.0 * visits[*s] - (uturn ? 10.0 : 0.0);
      if (score > best_score) best_score = score, best = *s;
    }
    if (best == graph::kNone) break;  // only tunnels ahead
    r.push_back(best);
    ++visits[best];
  }
  route = r;
  return route;
}

std::vector<Pose> samplePoses(const graph::StreetGraph& g, const std::vector<uint32_t>& route, double step_m,
                              double look_ahead_m, double lateral_m) {
  // Flatten the route into one polyline with the cell of each point.
  std::vector<glm::dvec2> pts;
  std::vector<uint32_t> cell_of;
  std::vector<double> arc;
  for (uint32_t h : route) {
    const auto& e = g.halfedges[h];
    for (uint32_t i = pts.empty() ? 0 : 1; i < e.pts_count; ++i) {
      const glm::dvec2 p = g.points[e.pts_begin + i];
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

}  // namespace blvd::cli
