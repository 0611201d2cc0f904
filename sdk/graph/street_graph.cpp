#include "graph/street_graph.h"

#include <cmath>
#include <numeric>

namespace blvd::graph {

size_t StreetGraph::junctionCount() const {
  size_t n = 0;
  for (const Vertex& v : vertices)
    if (v.kind == VertexKind::Junction || v.kind == VertexKind::DeadEnd) ++n;
  return n;
}

size_t StreetGraph::componentCount() const {
  std::vector<uint32_t> parent(vertices.size());
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const HalfEdge& h : halfedges) {
    uint32_t a = find(h.origin), b = find(halfedges[h.twin].origin);
    if (a != b) parent[a] = b;
  }
  size_t n = 0;
  for (uint32_t i = 0; i < parent.size(); ++i)
    if (find(i) == i) ++n;
  return n;
}

std::vector<std::string> checkInvariants(const StreetGraph& g) {
  std::vector<std::string> bad;
  auto report = [&](const std::string& s) {
    if (bad.size() < 50) bad.push_back(s);
  };
  const uint32_t H = static_cast<uint32_t>(g.halfedges.size());
  const uint32_t V = static_cast<uint32_t>(g.vertices.size());
  const uint32_t F = static_cast<uint32_t>(g.faces.size());
  if (H % 2) report("odd number of half-edges");
  for (uint32_t h = 0; h < H; ++h) {
    const HalfEdge& e = g.halfedges[h];
    const std::string id = "half-edge " + std::to_string(h);
    if (e.twin >= H) { report(id + ": no twin"); continue; }
    if (e.next >= H) { report(id + ": no next"); continue; }
    if (e.face >= F) { report(id + ": no face"); continue; }
    if (e.origin >= V) { report(id + ": no origin"); continue; }
    if (e.twin == h || g.halfedges[e.twin].twin != h) report(id + ": twin(twin) != self");
    if (g.halfedges[e.next].origin != g.halfedges[e.twin].origin) report(id + ": next does not start at its end");
    if (g.halfedges[e.next].face != e.face) report(id + ": next has another face");
    if (e.pts_count < 2 || e.pts_begin + e.pts_count > g.points.size()) {
      report(id + ": bad polyline");
      continue;
    }
    const glm::dvec2 a = g.points[e.pts_begin], b = g.points[e.pts_begin + e.pts_count - 1];
    const glm::dvec2 va = g.vertices[e.origin].p, vb = g.vertices[g.halfedges[e.twin].origin].p;
    if (std::abs(a.x - va.x) + std::abs(a.y - va.y) > 1e-3 || std::abs(b.x - vb.x) + std::abs(b.y - vb.y) > 1e-3)
      report(id + ": polyline does not join its vertices");
  }
  if (!bad.empty()) return bad;
  // Walking next from any half-edge returns to it (face cycles are closed).
  std::vector<uint8_t> seen(H, 0);
  for (uint32_t h = 0; h < H; ++h) {
    if (seen[h]) continue;
    uint32_t x = h;
    uint32_t steps = 0;
    do {
      if (seen[x]) { report("half-edge " + std::to_string(x) + " is on two face cycles"); break; }
      seen[x] = 1;
      x = g.halfedges[x].next;
    } while (x != h && ++steps <= H);
    if (steps > H) report("face cycle from half-edge " + std::to_string(h) + " does not close");
  }
  for (uint32_t f = 0; f < F; ++f) {
    const Face& face = g.faces[f];
    if (!face.unbounded && (face.halfedge >= H || g.halfedges[face.halfedge].face != f))
      report("face " + std::to_string(f) + ": boundary half-edge is not on it");
  }
  // A tiled benchmark package is several planar maps side by side, each with
  // its own unbounded face (sdk/bake/tile.h), so Euler counts them: with U
  // unbounded faces V - E + F = U + C (U = 1 for one city).
  long long unbounded = 0;
  for (const Face& face : g.faces) unbounded += face.unbounded;
  const long long euler = static_cast<long long>(V) - static_cast<long long>(H / 2) + static_cast<long long>(F);
  const long long expect = unbounded + static_cast<long long>(g.componentCount());
  if (euler != expect)
    report("Euler: V - E + F = " + std::to_string(euler) + ", expected U + C = " + std::to_string(expect) + " (" +
           std::to_string(unbounded) + " unbounded faces)");
  auto checkCsr = [&](const Csr& c, uint32_t limit, const char* name) {
    if (c.size() != H) { report(std::string(name) + ": not one list per cell"); return; }
    for (size_t i = 0; i + 1 < c.offsets.size(); ++i)
      if (c.offsets[i] > c.offsets[i + 1] || c.offsets[i + 1] > c.items.size()) {
        report(std::string(name) + ": bad offsets");
        return;
      }
    for (uint32_t x : c.items)
      if (x >= limit) { report(std::string(name) + ": item out of range"); return; }
  };
  checkCsr(g.successors, H, "successors");
  checkCsr(g.predecessors, H, "predecessors");
  checkCsr(g.local_blocks, F, "local blocks");
  return bad;
}

const char* roadClassName(RoadClass c) {
  switch (c) {
    case RoadClass::Motorway: return "motorway";
    case RoadClass::Trunk: return "trunk";
    case RoadClass::Primary: return "primary";
    case RoadClass::Secondary: return "secondary";
    case RoadClass::Tertiary: return "tertiary";
    case RoadClass::Unclassified: return "unclassified";
    case RoadClass::Residential: return "residential";
    case RoadClass::LivingStreet: return "living_street";
    case RoadClass::Service: return "service";
    case RoadClass::Link: return "link";
    case RoadClass::Other: return "other";
  }
  return "other";
}

glm::dvec2 cellDirection(const StreetGraph& g, uint32_t h, bool at_end) {
  const HalfEdge& e = g.halfedges[h];
  if (e.pts_count < 2) return {1, 0};
  const glm::dvec2* p = &g.points[e.pts_begin];
  const glm::dvec2 d = at_end ? p[e.pts_count - 1] - p[e.pts_count - 2] : p[1] - p[0];
  const double l = std::sqrt(d.x * d.x + d.y * d.y);
  return l > 0 ? d / l : glm::dvec2(1, 0);
}

}  // namespace blvd::graph
