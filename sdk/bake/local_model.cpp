// Local models widened by distance; see local_model.h.
#include "bake/local_model.h"

#include <algorithm>

#include "bake/plane_geometry.h"
#include "graph/segment_grid.h"

namespace blvd::bake {

void widenLocalModels(graph::StreetGraph& g, const std::vector<OsmBuilding>& buildings,
                      const std::vector<std::vector<uint32_t>>& face_buildings, double radius_m,
                      double junction_radius_m) {
  if (!(radius_m > 0) && !(junction_radius_m > 0)) return;
  // The streets near each footprint edge, from the graph's segment grid (one
  // half-edge of each twin pair is listed; its twin gets the same blocks).
  graph::SegmentGrid streets;
  streets.build(g);
  const size_t H = g.halfedges.size();
  std::vector<std::vector<uint32_t>> added(H);
  auto add = [&](uint32_t h, uint32_t f) {
    if (h < H && std::find(added[h].begin(), added[h].end(), f) == added[h].end()) added[h].push_back(f);
  };
  // Block f joins both directions of every street within radius_m of a..c.
  auto addNear = [&](glm::dvec2 a, glm::dvec2 c, uint32_t f) {
    const glm::dvec2 mid = 0.5 * (a + c);
    streets.query(mid.x, mid.y, 0.5 * glm::length(c - a) + radius_m, [&](const graph::SegmentGrid::Entry& e) {
      if (segmentDistance(g.points[e.point], g.points[e.point + 1], a, c) > radius_m) return;
      add(e.halfedge, f);
      add(g.halfedges[e.halfedge].twin, f);
    });
  };
  for (uint32_t f = 0; radius_m > 0 && f < face_buildings.size() && f < g.faces.size(); ++f) {
    if (g.faces[f].unbounded) continue;
    for (uint32_t b : face_buildings[f])
      for (const Polygon2& poly : buildings[b].polygons) {
        const std::vector<glm::dvec2>& r = poly.outer.pts;
        for (size_t k = 0; k < r.size(); ++k) addNear(r[k], r[(k + 1) % r.size()], f);
      }
  }
  // A block with no building is its ground and the halves of its streets: a
  // traffic island, the strip between two carriageways. Where that ground
  // comes within radius_m of a street, the viewer on that street sees it
  // below the horizon, steeper than a capture from the run's vantage point
  // holds it, and it costs a few dozen triangles as geometry.
  for (uint32_t h = 0; radius_m > 0 && h < H; ++h) {
    const graph::HalfEdge& e = g.halfedges[h];
    const uint32_t f = e.face;
    if (f >= g.faces.size() || g.faces[f].unbounded || (f < face_buildings.size() && !face_buildings[f].empty()))
      continue;
    for (uint32_t i = 0; i + 1 < e.pts_count; ++i) addNear(g.points[e.pts_begin + i], g.points[e.pts_begin + i + 1], f);
  }
  // The blocks on either side of every street within junction_radius_m of
  // the cell's end points: where a junction is drawn as several vertices a
  // few metres apart, the viewer crossing it stands on their ground. A street
  // and its twin share their end points: each pair is walked once.
  for (uint32_t h = 0; junction_radius_m > 0 && h < H; ++h) {
    const graph::HalfEdge& e = g.halfedges[h];
    if (e.pts_count == 0 || e.twin < h) continue;
    for (const glm::dvec2 p : {g.points[e.pts_begin], g.points[e.pts_begin + e.pts_count - 1]})
      streets.query(p.x, p.y, junction_radius_m, [&](const graph::SegmentGrid::Entry& s) {
        if (pointSegmentDistance(p, g.points[s.point], g.points[s.point + 1]) > junction_radius_m) return;
        for (const uint32_t side : {s.halfedge, g.halfedges[s.halfedge].twin}) {
          const uint32_t f = g.halfedges[side].face;
          if (f < g.faces.size() && !g.faces[f].unbounded) add(h, f), add(e.twin, f);
        }
      });
  }
  graph::Csr out;
  for (uint32_t h = 0; h < H; ++h) {
    std::vector<uint32_t> list(g.local_blocks.begin(h), g.local_blocks.end(h));
    std::sort(added[h].begin(), added[h].end());
    for (uint32_t f : added[h])
      if (std::find(list.begin(), list.end(), f) == list.end()) list.push_back(f);
    out.push(list);
  }
  g.local_blocks = std::move(out);
}

}  // namespace blvd::bake
