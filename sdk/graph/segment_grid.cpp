#include "graph/segment_grid.h"

#include <algorithm>
#include <cmath>

#include "core/bytes.h"
#include "graph/graph_source.h"

namespace blvd::graph {
namespace {

constexpr uint32_t kGridVersion = 1;

int clampTo(int v, int n) { return v < 0 ? 0 : v >= n ? n - 1 : v; }

// The grid's size is bounded by what it indexes, not by how far apart its
// points lie: at most kCellsPerSegment grid cells per listed segment (and at
// least kMinCells) and kEntriesPerSegment entries per segment. A graph spread
// thinly (a package whose points lie thousands of kilometres apart) gets
// coarser grid cells; a city keeps the cell size asked for.
constexpr double kMinCells = 65536;
constexpr double kCellsPerSegment = 4;
constexpr double kEntriesPerSegment = 16;

struct Box {
  double minx = 1e300, miny = 1e300, maxx = -1e300, maxy = -1e300;
  void add(glm::dvec2 p) {
    minx = std::min(minx, p.x), miny = std::min(miny, p.y);
    maxx = std::max(maxx, p.x), maxy = std::max(maxy, p.y);
  }
  bool empty() const { return minx > maxx; }
};

bool listed(uint32_t h, const HalfEdge& e, uint32_t halfedges) {
  return e.pts_count >= 2 && (e.twin == kNone || e.twin > h || e.twin >= halfedges);
}

// Calls fn(a, b, point index of a) for each listed segment.
template <class G, class Fn>
void forEachSegment(const G& g, Fn&& fn) {
  const uint32_t n = g.cellCount();
  for (uint32_t h = 0; h < n; ++h) {
    const HalfEdge e = g.halfedge(h);
    if (!listed(h, e, n)) continue;
    for (uint32_t i = 0; i + 1 < e.pts_count; ++i) fn(h, e.pts_begin + i);
  }
}

// The grid cells the bounding box of segment ab touches.
void cellSpan(const GridShape& s, glm::dvec2 a, glm::dvec2 b, int* x0, int* x1, int* y0, int* y1) {
  const double inv = 1.0 / s.cell;
  *x0 = clampTo(static_cast<int>((std::min(a.x, b.x) - s.ox) * inv), s.nx);
  *x1 = clampTo(static_cast<int>((std::max(a.x, b.x) - s.ox) * inv), s.nx);
  *y0 = clampTo(static_cast<int>((std::min(a.y, b.y) - s.oy) * inv), s.ny);
  *y1 = clampTo(static_cast<int>((std::max(a.y, b.y) - s.oy) * inv), s.ny);
}

// The cell size, from cell_m up by doubling, at which the grid over box holds
// at most the cells and entries its segments allow.
template <class G>
GridShape chooseShape(const G& g, const Box& box, double cell_m, double segments) {
  GridShape s;
  s.ox = box.minx;
  s.oy = box.miny;
  const double max_cells = std::max(kMinCells, kCellsPerSegment * segments);
  const double max_entries = kEntriesPerSegment * segments;
  for (s.cell = cell_m;; s.cell *= 2) {
    const double nx = std::max(1.0, std::ceil((box.maxx - box.minx) / s.cell + 1e-9));
    const double ny = std::max(1.0, std::ceil((box.maxy - box.miny) / s.cell + 1e-9));
    if (nx * ny > max_cells) continue;
    s.nx = static_cast<int>(nx);
    s.ny = static_cast<int>(ny);
    double entries = 0;
    forEachSegment(g, [&](uint32_t, uint32_t pi) {
      int x0, x1, y0, y1;
      cellSpan(s, g.point(pi), g.point(pi + 1), &x0, &x1, &y0, &y1);
      entries += double(x1 - x0 + 1) * (y1 - y0 + 1);
    });
    if (entries <= max_entries || s.nx * s.ny == 1) return s;
  }
}

// Builds the grid over any graph G with halfedge(h), point(i) and cellCount().
template <class G>
void buildGrid(const G& g, double cell_m, GridShape& shape, std::vector<uint32_t>& offsets,
               std::vector<SegmentGrid::Entry>& entries) {
  offsets.clear();
  entries.clear();
  Box box;
  double segments = 0;
  forEachSegment(g, [&](uint32_t, uint32_t pi) {
    box.add(g.point(pi));
    box.add(g.point(pi + 1));
    ++segments;
  });
  shape = GridShape{};
  shape.cell = cell_m > 0 ? cell_m : 50.0;
  if (box.empty()) {
    offsets.assign(1, 0);
    return;
  }
  shape = chooseShape(g, box, shape.cell, segments);
  const size_t n = shape.cellCount();
  // Two passes (count, then fill) so the CSR arrays are allocated once.
  std::vector<uint32_t> counts(n + 1, 0);
  for (int pass = 0; pass < 2; ++pass) {
    forEachSegment(g, [&](uint32_t h, uint32_t pi) {
      int x0, x1, y0, y1;
      cellSpan(shape, g.point(pi), g.point(pi + 1), &x0, &x1, &y0, &y1);
      for (int gy = y0; gy <= y1; ++gy)
        for (int gx = x0; gx <= x1; ++gx) {
          const size_t c = static_cast<size_t>(gy) * shape.nx + gx;
          if (pass == 0) ++counts[c + 1];
          else entries[counts[c]++] = SegmentGrid::Entry{h, pi};
        }
    });
    if (pass == 0) {
      for (size_t c = 0; c < n; ++c) counts[c + 1] += counts[c];
      offsets = counts;
      entries.resize(counts[n]);
    }
  }
}

// A StreetGraph seen through the accessors buildGrid uses.
struct WholeGraph {
  const StreetGraph& g;
  uint32_t cellCount() const { return static_cast<uint32_t>(g.halfedges.size()); }
  const HalfEdge& halfedge(uint32_t h) const { return g.halfedges[h]; }
  glm::dvec2 point(uint32_t i) const { return g.points[i]; }
};

}  // namespace

bool GridShape::cellsNear(double x, double y, double r, int* x0, int* x1, int* y0, int* y1) const {
  if (nx == 0 || !(r >= 0)) return false;
  if (x + r < ox || y + r < oy || x - r > ox + nx * cell || y - r > oy + ny * cell) return false;
  const double inv = 1.0 / cell;
  *x0 = clampTo(static_cast<int>((x - r - ox) * inv), nx);
  *x1 = clampTo(static_cast<int>((x + r - ox) * inv), nx);
  *y0 = clampTo(static_cast<int>((y - r - oy) * inv), ny);
  *y1 = clampTo(static_cast<int>((y + r - oy) * inv), ny);
  return true;
}

void SegmentGrid::build(const StreetGraph& g, double cell_m) { buildGrid(WholeGraph{g}, cell_m, shape_, offsets_, entries_); }

void SegmentGrid::build(const GraphSource& g, double cell_m) { buildGrid(g, cell_m, shape_, offsets_, entries_); }

std::vector<uint8_t> serializeSegmentGrid(const SegmentGrid& grid) {
  core::ByteWriter w;
  const GridShape& s = grid.shape();
  w.put(kGridVersion);
  w.put(s.ox);
  w.put(s.oy);
  w.put(s.cell);
  w.put<uint32_t>(static_cast<uint32_t>(s.nx));
  w.put<uint32_t>(static_cast<uint32_t>(s.ny));
  w.put<uint32_t>(static_cast<uint32_t>(grid.entryCount()));
  for (uint32_t o : grid.offsets()) w.put(o);
  for (const SegmentGrid::Entry& e : grid.entries()) {
    w.put(e.halfedge);
    w.put(e.point);
  }
  return std::move(w.bytes());
}

StoredGrid parseGridShape(const uint8_t* data, size_t size, uint64_t file_offset) {
  core::ByteReader r(data, size, "package section SIDX", file_offset);
  if (r.get<uint32_t>() != kGridVersion) r.fail("unknown grid version");
  StoredGrid g;
  g.shape.ox = r.get<double>();
  g.shape.oy = r.get<double>();
  g.shape.cell = r.get<double>();
  const uint32_t nx = r.get<uint32_t>(), ny = r.get<uint32_t>();
  g.entries = r.get<uint32_t>();
  if (!std::isfinite(g.shape.ox) || !std::isfinite(g.shape.oy) || !(g.shape.cell >= 1 && g.shape.cell <= 1e5))
    r.fail("grid origin or cell size is not a finite position and size");
  if ((nx == 0) != (ny == 0) || nx > (1u << 20) || ny > (1u << 20)) r.fail("grid dimensions out of range");
  g.shape.nx = static_cast<int>(nx);
  g.shape.ny = static_cast<int>(ny);
  const uint64_t want = kGridHeaderBytes + (uint64_t(nx) * ny + 1) * 4 + uint64_t(g.entries) * 8;
  if (want != size) r.fail("section is " + std::to_string(size) + " bytes, its counts say " + std::to_string(want));
  g.offsets_at = kGridHeaderBytes;
  g.entries_at = kGridHeaderBytes + (size_t(nx) * ny + 1) * 4;
  return g;
}

}  // namespace blvd::graph
