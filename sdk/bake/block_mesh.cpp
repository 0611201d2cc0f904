#include "bake/block_mesh.h"

#include <cmath>

#include <glm/geometric.hpp>

#include "bake/extrude.h"
#include "bake/triangulate.h"

namespace blvd::bake {
namespace {

void pushVertex(geo::MeshData& m, const glm::dvec2& en, double up, const uint8_t rgba[4]) {
  float p[3];
  geo::enuToGltf(en.x, en.y, up, p);
  m.positions.insert(m.positions.end(), p, p + 3);
  m.normals.insert(m.normals.end(), {0.f, 1.f, 0.f});
  m.colors.insert(m.colors.end(), rgba, rgba + 4);
}

glm::dvec2 leftOf(glm::dvec2 d) { return {-d.y, d.x}; }

constexpr double kRibbonEndOverlap = 0.5;  // metres

// Secondary and up: drawn darker, and above the others where they overlap.
bool isMajor(const graph::HalfEdge& e) { return e.road_class <= graph::RoadClass::Secondary; }

}  // namespace

double streetLift(const graph::HalfEdge& e) {
  const int rank = (isMajor(e) ? 1 : 0) + (e.flags & graph::kBridge ? 2 : 0);
  return kStreetLift + rank * kStreetRankLift;
}

void appendHalfStreet(const graph::StreetGraph& g, uint32_t h, geo::MeshData& out) {
  const graph::HalfEdge& e = g.halfedges[h];
  if (e.flags & graph::kTunnel) return;
  static const uint8_t asphalt[4] = {88, 90, 96, 255};
  static const uint8_t major[4] = {78, 80, 88, 255};
  const uint8_t* col = isMajor(e) ? major : asphalt;
  const glm::dvec2* p = &g.points[e.pts_begin];
  const size_t n = e.pts_count;
  const double half = 0.5 * e.width;
  const double lift = streetLift(e);
  const auto base = static_cast<uint32_t>(out.vertexCount());
  size_t emitted = 0;
  for (size_t i = 0; i < n; ++i) {
    glm::dvec2 d0 = i > 0 ? p[i] - p[i - 1] : p[1] - p[0];
    glm::dvec2 d1 = i + 1 < n ? p[i + 1] - p[i] : p[n - 1] - p[n - 2];
    const double l0 = glm::length(d0), l1 = glm::length(d1);
    if (l0 < 1e-9 || l1 < 1e-9) {
      d0 = d1 = (l0 < 1e-9 ? d1 : d0);
    }
    const glm::dvec2 n0 = leftOf(glm::normalize(d0)), n1 = leftOf(glm::normalize(d1));
    glm::dvec2 m = n0 + n1;
    const double ml = glm::length(m);
    // Mitre: scale the averaged normal by 1/cos(half the turn), capped so
    // hairpins do not throw spikes across the block.
    m = ml < 1e-6 ? n0 : m / ml;
    const double c = std::max(0.5, glm::dot(m, n0));
    // The ends reach kRibbonEndOverlap past the street's end points, so the
    // ribbons of two streets that meet at an angle overlap at the junction
    // instead of leaving a seam that the street beneath shows through.
    glm::dvec2 at = p[i];
    const glm::dvec2 end_dir = i == 0 ? -d1 : d0;
    if ((i == 0 || i + 1 == n) && glm::length(end_dir) > 1e-9) at += glm::normalize(end_dir) * kRibbonEndOverlap;
    // The inner edge reaches 15 cm past the centre line so the two halves of a
    // street overlap instead of leaving pixel cracks where they meet.
    pushVertex(out, at - m * (0.15 / c), lift, col);
    pushVertex(out, at + m * (half / c), lift, col);
    ++emitted;
  }
  for (uint32_t i = 0; i + 1 < emitted; ++i) {
    const uint32_t c0 = base + 2 * i, o0 = c0 + 1, c1 = c0 + 2, o1 = c0 + 3;
    out.indices.insert(out.indices.end(), {c0, c1, o1, c0, o1, o0});
  }
}

bool appendBlockGround(const graph::StreetGraph& g, uint32_t f, const std::function<bool(glm::dvec2)>& inside,
                       geo::MeshData& out, std::string& why) {
  if (g.faces[f].unbounded) {
    why = "unbounded face";
    return false;
  }
  std::vector<Segment2> segs;
  for (uint32_t h = 0; h < g.halfedges.size(); ++h) {
    const graph::HalfEdge& e = g.halfedges[h];
    if (e.face != f) continue;
    for (uint32_t i = 0; i + 1 < e.pts_count; ++i)
      segs.push_back({g.points[e.pts_begin + i], g.points[e.pts_begin + i + 1]});
  }
  Triangulation t;
  if (!triangulateSegments(segs, inside, t, why)) return false;
  static const uint8_t pavement[4] = {196, 190, 178, 255};
  const auto base = static_cast<uint32_t>(out.vertexCount());
  for (const glm::dvec2& v : t.vertices) pushVertex(out, v, kGroundLift, pavement);
  for (uint32_t i : t.indices) out.indices.push_back(base + i);
  return true;
}

bool buildingAnchor(const OsmBuilding& b, glm::dvec2& p) {
  for (const Polygon2& poly : b.polygons) {
    Triangulation t;
    std::string why;
    if (!triangulate(poly, t, why)) continue;
    double best = -1;
    for (size_t i = 0; i + 2 < t.indices.size(); i += 3) {
      const glm::dvec2 a = t.vertices[t.indices[i]], c = t.vertices[t.indices[i + 1]], d = t.vertices[t.indices[i + 2]];
      const double area2 = std::abs((c.x - a.x) * (d.y - a.y) - (d.x - a.x) * (c.y - a.y));
      if (area2 > best) {
        best = area2;
        p = (a + c + d) / 3.0;
      }
    }
    if (best > 0) return true;
  }
  return false;
}

bool appendBuilding(const OsmBuilding& b, geo::MeshData& out, std::string& why) {
  uint8_t wall[4], roof[4];
  buildingColour(static_cast<uint64_t>(b.id), wall);
  roofColour(wall, roof);
  bool any = false;
  for (const Polygon2& poly : b.polygons) {
    std::string w;
    if (extrudeBuilding(poly, b.min_height, b.height, wall, roof, out, w)) any = true;
    else why = w;
  }
  return any;
}

}  // namespace blvd::bake
