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

class GraphSource;

// Where the grid lies: origin, cell size and cells across. Shared by the grid
// in memory and the one a package stores (the SIDX section, read by pages).
struct GridShape {
  double ox = 0, oy = 0, cell = 50;
  int nx = 0, ny = 0;
  // The grid cells overlapping the square of half-size r around (x, y);
  // false when there are none.
  bool cellsNear(double x, double y, double r, int* x0, int* x1, int* y0, int* y1) const;
  size_t cellCount() const { return static_cast<size_t>(nx) * ny; }
};

class SegmentGrid {
 public:
  struct Entry {
    uint32_t halfedge;  // the half-edge of the pair that is listed
    uint32_t point;     // index into StreetGraph::points of the segment's first point
  };

  // cell_m <= 0 picks 50 m. The graph must outlive the grid.
  void build(const StreetGraph& g, double cell_m = 0);
  // The same from any source (a paged package without a stored grid).
  void build(const GraphSource& g, double cell_m = 0);

  // Calls fn(const Entry&) for each entry in the grid cells overlapping the
  // square of half-size r around (x, y).
  template <class Fn>
  void query(double x, double y, double r, Fn&& fn) const {
    int x0, x1, y0, y1;
    if (!shape_.cellsNear(x, y, r, &x0, &x1, &y0, &y1)) return;
    for (int gy = y0; gy <= y1; ++gy)
      for (int gx = x0; gx <= x1; ++gx) {
        const size_t c = static_cast<size_t>(gy) * shape_.nx + gx;
        for (uint32_t i = offsets_[c]; i < offsets_[c + 1]; ++i) fn(entries_[i]);
      }
  }

  const GridShape& shape() const { return shape_; }
  const std::vector<uint32_t>& offsets() const { return offsets_; }  // cellCount() + 1
  const std::vector<Entry>& entries() const { return entries_; }
  size_t entryCount() const { return entries_.size(); }
  int columns() const { return shape_.nx; }
  int rows() const { return shape_.ny; }
  double cellSize() const { return shape_.cell; }
  size_t bytes() const { return offsets_.capacity() * sizeof(uint32_t) + entries_.capacity() * sizeof(Entry); }

 private:
  GridShape shape_;
  std::vector<uint32_t> offsets_;
  std::vector<Entry> entries_;
};

// The SIDX section: a grid built with cell_m, as the runtime pages it
// (docs/package-format.md has the layout). parseGridShape checks the header
// and that the section holds the offsets and entries it announces, and
// returns where they start; it throws core::Error(Corrupt) naming the offset.
std::vector<uint8_t> serializeSegmentGrid(const SegmentGrid& grid);
inline constexpr size_t kGridHeaderBytes = 4 + 3 * 8 + 4 * 3;  // version, ox oy cell, nx ny entries
struct StoredGrid {
  GridShape shape;
  uint32_t entries = 0;
  size_t offsets_at = 0, entries_at = 0;  // byte offsets in the section
};
StoredGrid parseGridShape(const uint8_t* data, size_t size, uint64_t file_offset);

}  // namespace blvd::graph
