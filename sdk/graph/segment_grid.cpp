#include "graph/segment_grid.h"

#include <algorithm>
#include <cmath>

namespace blvd::graph {

void SegmentGrid::build(const StreetGraph& g, double cell_m) {
  cell_ = cell_m > 0 ? cell_m : 50.0;
  inv_ = 1.0 / cell_;
  offsets_.clear();
  entries_.clear();
  nx_ = ny_ = 0;
  double minx = 1e300, miny = 1e300, maxx = -1e300, maxy = -1e300;
  auto listed = [&](uint32_t h) {
    const auto& e = g.halfedges[h];
    return e.pts_count >= 2 && (e.twin == kNone || e.twin > h || e.twin >= g.halfedges.size());
  };
  for (uint32_t h = 0; h < g.halfedges.size(); ++h) {
    if (!listed(h)) continue;
    const auto& e = g.halfedges[h];
    for (uint32_t i = 0; i < e.pts_count; ++i) {
      const glm::dvec2 p = g.points[e.pts_begin + i];
      minx = std::min(minx, p.x), miny = std::min(miny, p.y);
      maxx = std::max(maxx, p.x), maxy = std::max(maxy, p.y);
    }
  }
  if (minx > maxx) return;
  ox_ = minx;
  oy_ = miny;
  nx_ = std::max(1, static_cast<int>(std::ceil((maxx - minx) * inv_ + 1e-9)));
  ny_ = std::max(1, static_cast<int>(std::ceil((maxy - miny) * inv_ + 1e-9)));
  const size_t cells = static_cast<size_t>(nx_) * ny_;
  // Two passes (count, then fill) so the CSR arrays are allocated once.
  std::vector<uint32_t> counts(cells + 1, 0);
  auto forEachCell = [&](glm::dvec2 a, glm::dvec2 b, auto&& fn) {
    const int x0 = clampX(static_cast<int>((std::min(a.x, b.x) - ox_) * inv_));
    const int x1 = clampX(static_cast<int>((std::max(a.x, b.x) - ox_) * inv_));
    const int y0 = clampY(static_cast<int>((std::min(a.y, b.y) - oy_) * inv_));
    const int y1 = clampY(static_cast<int>((std::max(a.y, b.y) - oy_) * inv_));
    for (int gy = y0; gy <= y1; ++gy)
      for (int gx = x0; gx <= x1; ++gx) fn(static_cast<size_t>(gy) * nx_ + gx);
  };
  for (int pass = 0; pass < 2; ++pass) {
    for (uint32_t h = 0; h < g.halfedges.size(); ++h) {
      if (!listed(h)) continue;
      const auto& e = g.halfedges[h];
      for (uint32_t i = 0; i + 1 < e.pts_count; ++i) {
        const uint32_t pi = e.pts_begin + i;
        forEachCell(g.points[pi], g.points[pi + 1], [&](size_t c) {
          if (pass == 0) ++counts[c + 1];
          else entries_[counts[c]++] = Entry{h, pi};
        });
      }
    }
    if (pass == 0) {
      for (size_t c = 0; c < cells; ++c) counts[c + 1] += counts[c];
      offsets_ = counts;
      entries_.resize(counts[cells]);
    }
  }
}

}  // namespace blvd::graph
