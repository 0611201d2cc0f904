#include "graph/graph_source.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace blvd::graph {

MemoryGraph::MemoryGraph(const StreetGraph& g, double grid_cell_m) : g_(g) { grid_.build(g_, grid_cell_m); }

const Csr& MemoryGraph::csr(CellList l) const {
  return l == CellList::Successors ? g_.successors : l == CellList::Predecessors ? g_.predecessors : g_.local_blocks;
}

void MemoryGraph::listBounds(CellList list, uint32_t h, uint32_t* first, uint32_t* last) const {
  const Csr& c = csr(list);
  if (size_t(h) + 1 >= c.offsets.size()) {  // a graph built without this list
    *first = *last = 0;
    return;
  }
  *first = c.offsets[h];
  *last = c.offsets[h + 1];
}

void MemoryGraph::segmentsNear(double x, double y, double r, EntryFn fn, void* ctx) const {
  grid_.query(x, y, r, [&](const SegmentGrid::Entry& e) { fn(e, ctx); });
}

glm::dvec2 cellDirection(const GraphSource& g, uint32_t h, bool at_end) {
  const HalfEdge e = g.halfedge(h);
  if (e.pts_count < 2) return {1, 0};
  const uint32_t i = at_end ? e.pts_begin + e.pts_count - 2 : e.pts_begin;
  const glm::dvec2 d = g.point(i + 1) - g.point(i);
  const double l = std::sqrt(d.x * d.x + d.y * d.y);
  return l > 0 ? d / l : glm::dvec2(1, 0);
}

}  // namespace blvd::graph

namespace blvd::graph {

double outsideStreets(const GraphSource& g, double x, double y) {
  const GridShape s = g.gridShape();
  if (s.nx <= 0 || s.ny <= 0) return std::numeric_limits<double>::infinity();  // no street: nowhere is on it
  const double dx = std::max({s.ox - x, 0.0, x - (s.ox + s.nx * s.cell)});
  const double dy = std::max({s.oy - y, 0.0, y - (s.oy + s.ny * s.cell)});
  return std::hypot(dx, dy);
}

}  // namespace blvd::graph
