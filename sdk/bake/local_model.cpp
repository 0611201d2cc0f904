// Local models widened by distance; see local_model.h.
#include "bake/local_model.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

namespace blvd::bake {
namespace {

struct FootprintEdge {
  glm::dvec2 a, b;
  uint32_t face;
};

double pointToSegment(glm::dvec2 p, glm::dvec2 a, glm::dvec2 b) {
  const glm::dvec2 d = b - a;
  const double len2 = glm::dot(d, d);
  const double t = len2 > 0 ? std::clamp(glm::dot(p - a, d) / len2, 0.0, 1.0) : 0.0;
  return glm::length(a + d * t - p);
}

double cross(glm::dvec2 a, glm::dvec2 b) { return a.x * b.y - a.y * b.x; }

// Distance between segments pq and ab in the plane (0 when they cross).
double segmentDistance(glm::dvec2 p, glm::dvec2 q, glm::dvec2 a, glm::dvec2 b) {
  const double d1 = cross(q - p, a - p), d2 = cross(q - p, b - p);
  const double d3 = cross(b - a, p - a), d4 = cross(b - a, q - a);
  if (((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0)) && d1 != 0 && d2 != 0 && d3 != 0 && d4 != 0) return 0.0;
  return std::min({pointToSegment(p, a, b), pointToSegment(q, a, b), pointToSegment(a, p, q), pointToSegment(b, p, q)});
}

// Footprint edges bucketed on a square grid, so that a street asks only the
// buckets within the radius.
class EdgeGrid {
 public:
  EdgeGrid(std::vector<FootprintEdge> edges, double cell) : edges_(std::move(edges)), cell_(cell) {
    if (edges_.empty()) return;
    lo_ = hi_ = edges_[0].a;
    for (const FootprintEdge& e : edges_) lo_ = glm::min(lo_, glm::min(e.a, e.b)), hi_ = glm::max(hi_, glm::max(e.a, e.b));
    nx_ = int((hi_.x - lo_.x) / cell_) + 1;
    ny_ = int((hi_.y - lo_.y) / cell_) + 1;
    buckets_.resize(size_t(nx_) * size_t(ny_));
    for (uint32_t i = 0; i < edges_.size(); ++i) {
      int x0, x1, y0, y1;
      range(glm::min(edges_[i].a, edges_[i].b), glm::max(edges_[i].a, edges_[i].b), x0, x1, y0, y1);
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) buckets_[size_t(y) * size_t(nx_) + size_t(x)].push_back(i);
    }
  }
  // Calls fn(edge) for the edges in the buckets overlapping the box [lo, hi]
  // (an edge may come more than once).
  template <class Fn>
  void visit(glm::dvec2 lo, glm::dvec2 hi, Fn&& fn) const {
    if (edges_.empty() || hi.x < lo_.x || hi.y < lo_.y || lo.x > hi_.x || lo.y > hi_.y) return;
    int x0, x1, y0, y1;
    range(lo, hi, x0, x1, y0, y1);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x)
        for (uint32_t i : buckets_[size_t(y) * size_t(nx_) + size_t(x)]) fn(edges_[i]);
  }

 private:
  void range(glm::dvec2 lo, glm::dvec2 hi, int& x0, int& x1, int& y0, int& y1) const {
    x0 = std::clamp(int(std::floor((lo.x - lo_.x) / cell_)), 0, nx_ - 1);
    x1 = std::clamp(int(std::floor((hi.x - lo_.x) / cell_)), 0, nx_ - 1);
    y0 = std::clamp(int(std::floor((lo.y - lo_.y) / cell_)), 0, ny_ - 1);
    y1 = std::clamp(int(std::floor((hi.y - lo_.y) / cell_)), 0, ny_ - 1);
  }

  std::vector<FootprintEdge> edges_;
  double cell_;
  glm::dvec2 lo_{0.0}, hi_{0.0};
  int nx_ = 0, ny_ = 0;
  std::vector<std::vector<uint32_t>> buckets_;
};

std::vector<FootprintEdge> footprintEdges(const graph::StreetGraph& g, const std::vector<OsmBuilding>& buildings,
                                          const std::vector<std::vector<uint32_t>>& face_buildings) {
  std::vector<FootprintEdge> edges;
  for (uint32_t f = 0; f < face_buildings.size() && f < g.faces.size(); ++f) {
    if (g.faces[f].unbounded) continue;
    for (uint32_t b : face_buildings[f])
      for (const Polygon2& poly : buildings[b].polygons) {
        const std::vector<glm::dvec2>& r = poly.outer.pts;
        for (size_t k = 0; k < r.size(); ++k) edges.push_back({r[k], r[(k + 1) % r.size()], f});
      }
  }
  return edges;
}

// The bounded blocks with a footprint edge within `radius` of half-edge h's polyline.
std::vector<uint32_t> blocksNear(const graph::StreetGraph& g, uint32_t h, const EdgeGrid& grid, double radius) {
  std::vector<uint32_t> near;
  const graph::HalfEdge& e = g.halfedges[h];
  for (uint32_t i = e.pts_begin; i + 1 < e.pts_begin + e.pts_count; ++i) {
    const glm::dvec2 p = g.points[i], q = g.points[i + 1];
    grid.visit(glm::min(p, q) - radius, glm::max(p, q) + radius, [&](const FootprintEdge& fe) {
      if (std::find(near.begin(), near.end(), fe.face) == near.end() && segmentDistance(p, q, fe.a, fe.b) <= radius)
        near.push_back(fe.face);
    });
  }
  std::sort(near.begin(), near.end());
  return near;
}

}  // namespace

void widenLocalModels(graph::StreetGraph& g, const std::vector<OsmBuilding>& buildings,
                      const std::vector<std::vector<uint32_t>>& face_buildings, double radius_m) {
  if (!(radius_m > 0)) return;
  const EdgeGrid grid(footprintEdges(g, buildings, face_buildings), std::max(radius_m, 16.0));
  const size_t H = g.halfedges.size();
  std::vector<std::vector<uint32_t>> lists(H);
  for (uint32_t h = 0; h < H; ++h) {
    lists[h].assign(g.local_blocks.begin(h), g.local_blocks.end(h));
    const uint32_t twin = g.halfedges[h].twin;
    if (twin != graph::kNone && twin < h) continue;  // the twin's street is the same polyline, reversed
    for (uint32_t f : blocksNear(g, h, grid, radius_m)) {
      if (std::find(lists[h].begin(), lists[h].end(), f) == lists[h].end()) lists[h].push_back(f);
    }
  }
  // The twins that came second take their first half-edge's additions.
  for (uint32_t h = 0; h < H; ++h) {
    const uint32_t twin = g.halfedges[h].twin;
    if (twin == graph::kNone || twin > h) continue;
    const std::vector<uint32_t> added(lists[twin].begin() + g.local_blocks.count(twin), lists[twin].end());
    for (uint32_t f : added)
      if (std::find(lists[h].begin(), lists[h].end(), f) == lists[h].end()) lists[h].push_back(f);
  }
  graph::Csr out;
  for (const auto& l : lists) out.push(l);
  g.local_blocks = std::move(out);
}

}  // namespace blvd::bake
