// A uniform grid over the street graph's polyline segments, built once, for
// the candidate search of the map matcher (track) and the runtime's nearest
// cell (stream): "which streets pass within r of p".
//
// One entry per segment of one half-edge of each twin pair (the twin's
// polyline is the same points reversed, so the matcher derives it), stored
// CSR-style per grid cell. A segment is listed in every grid cell its bounding
// box touches, so a query can meet it more than once; callers deduplicate (the
// matcher keeps the nearest segment per half-edge anyway).
//
// Contract: build() allocates; query() does not, and is const (any number of
// threads may query one built grid).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "graph/street_graph.h"

namespace blvd::graph {

class SegmentGrid {
 public:
  struct Entry {
    uint32_t halfedge;  // the half-edge of the pair that is listed
    uint32_t point;     // index into StreetGraph::points of the segment's first point
  };

  // cell_m <= 0 picks 50 m. The graph must outlive the grid.
  void build(const StreetGraph& g, double cell_m = 0);

  // Calls fn(const Entry&) for each entry in the grid cells overlapping the
  // square of half-size r around (x, y).
  template <class Fn>
  void query(double x, double y, double r, Fn&& fn) const {
    if (nx_ == 0) return;
    const int x0 = clampX(static_cast<int>((x - r - ox_) * inv_)), x1 = clampX(static_cast<int>((x + r - ox_) * inv_));
    const int y0 = clampY(static_cast<int>((y - r - oy_) * inv_)), y1 = clampY(static_cast<int>((y + r - oy_) * inv_));
    if (x + r < ox_ || y + r < oy_ || x - r > ox_ + nx_ * cell_ || y - r > oy_ + ny_ * cell_) return;
    for (int gy = y0; gy <= y1; ++gy)
      for (int gx = x0; gx <= x1; ++gx) {
        const size_t c = static_cast<size_t>(gy) * nx_ + gx;
        for (uint32_t i = offsets_[c]; i < offsets_[c + 1]; ++i) fn(entries_[i]);
      }
  }

  size_t entryCount() const { return entries_.size(); }
  int columns() const { return nx_; }
  int rows() const { return ny_; }
  double cellSize() const { return cell_; }
  size_t bytes() const { return offsets_.capacity() * sizeof(uint32_t) + entries_.capacity() * sizeof(Entry); }

 private:
  int clampX(int v) const { return v < 0 ? 0 : v >= nx_ ? nx_ - 1 : v; }
  int clampY(int v) const { return v < 0 ? 0 : v >= ny_ ? ny_ - 1 : v; }

  double ox_ = 0, oy_ = 0, cell_ = 50, inv_ = 1.0 / 50;
  int nx_ = 0, ny_ = 0;
  std::vector<uint32_t> offsets_;
  std::vector<Entry> entries_;
};

}  // namespace blvd::graph
