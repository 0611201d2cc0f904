// Hand-built street graphs for the tracking tests: a builder that makes twin
// half-edges and successor lists (every outgoing street at the end vertex but
// the way back, unless it is a dead end), a T-junction and a grid city.
#pragma once
#include <cmath>
#include <cstdint>
#include <vector>

#include "graph/street_graph.h"

namespace blvd_test {

using blvd::graph::StreetGraph;

class GraphBuilder {
 public:
  uint32_t vertex(double x, double y) {
    blvd::graph::Vertex v;
    v.p = {x, y};
    g_.vertices.push_back(v);
    return static_cast<uint32_t>(g_.vertices.size() - 1);
  }
  // A street from vertex a to vertex b through `mid` points; returns the a->b half-edge (b->a is +1).
  uint32_t street(uint32_t a, uint32_t b, const std::vector<glm::dvec2>& mid = {}) {
    std::vector<glm::dvec2> pts{g_.vertices[a].p};
    pts.insert(pts.end(), mid.begin(), mid.end());
    pts.push_back(g_.vertices[b].p);
    const uint32_t h = static_cast<uint32_t>(g_.halfedges.size());
    for (int dir = 0; dir < 2; ++dir) {
      blvd::graph::HalfEdge e;
      e.origin = dir == 0 ? a : b;
      e.twin = dir == 0 ? h + 1 : h;
      e.pts_begin = static_cast<uint32_t>(g_.points.size());
      e.pts_count = static_cast<uint32_t>(pts.size());
      double len = 0;
      for (size_t i = 0; i < pts.size(); ++i) {
        const glm::dvec2 p = dir == 0 ? pts[i] : pts[pts.size() - 1 - i];
        if (i) len += std::hypot(p.x - g_.points.back().x, p.y - g_.points.back().y);
        g_.points.push_back(p);
      }
      e.length = static_cast<float>(len);
      e.width = 8;
      e.road_class = blvd::graph::RoadClass::Residential;
      g_.halfedges.push_back(e);
    }
    return h;
  }
  StreetGraph finish() {
    const size_t H = g_.halfedges.size();
    std::vector<std::vector<uint32_t>> out(g_.vertices.size()), pred(H);
    for (uint32_t h = 0; h < H; ++h) out[g_.halfedges[h].origin].push_back(h);
    g_.successors = {};
    g_.predecessors = {};
    for (uint32_t h = 0; h < H; ++h) {
      std::vector<uint32_t> s;
      const uint32_t v = g_.endVertex(h);
      for (uint32_t o : out[v])
        if (o != g_.halfedges[h].twin || out[v].size() == 1) s.push_back(o);
      for (uint32_t o : s) pred[o].push_back(h);
      g_.successors.push(s);
    }
    for (uint32_t h = 0; h < H; ++h) g_.predecessors.push(pred[h]);
    for (uint32_t h = 0; h < H; ++h)
      if (g_.vertices[g_.halfedges[h].origin].halfedge == blvd::graph::kNone) g_.vertices[g_.halfedges[h].origin].halfedge = h;
    return g_;
  }

 private:
  StreetGraph g_;
};

// A T-junction at the origin: a stem from (0, -200) north to J = (0, 0), then
// a branch north-west through (-20, 20) to (-150, 20) and one north-east
// through (20, 20) to (150, 20).
struct TJunction {
  StreetGraph g;
  uint32_t stem = 0, west = 0, east = 0;  // the half-edges driving away from the stem's start
};

inline TJunction makeTJunction() {
  GraphBuilder b;
  const uint32_t s = b.vertex(0, -200), j = b.vertex(0, 0), w = b.vertex(-150, 20), e = b.vertex(150, 20);
  TJunction t;
  t.stem = b.street(s, j);
  t.west = b.street(j, w, {{-20, 20}});
  t.east = b.street(j, e, {{20, 20}});
  t.g = b.finish();
  return t;
}

// n x n junctions `spacing` metres apart, every street two-way.
inline StreetGraph makeGrid(int n, double spacing) {
  GraphBuilder b;
  std::vector<uint32_t> v;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) v.push_back(b.vertex(x * spacing, y * spacing));
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      if (x + 1 < n) b.street(v[y * n + x], v[y * n + x + 1]);
      if (y + 1 < n) b.street(v[y * n + x], v[(y + 1) * n + x]);
    }
  return b.finish();
}

}  // namespace blvd_test
