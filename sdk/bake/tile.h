// `blvd bake --tile NxM`: a benchmark package holding N × M copies of the city
// (DESIGN "Measuring": memory on packages of 1× and 4× the city). Copies are
// laid out east (N) and north (M), each shifted by the city's extent plus a
// gap, and are *disconnected* components of the street graph: no street joins
// two copies, and each copy keeps its own unbounded face, so every copy's
// blocks, cells and per-cell data are exactly the original's. Copy 0 is the
// original, unshifted, with the original's ids: cell c, block b, junction j
// and blob i of copy k are c + k·cells, b + k·blocks, j + k·vertices and
// i + k·blobs. So a route (e.g. `--impostor-route auto:N --seed S`, chosen on
// the original graph) names the same cells, at the same coordinates, in the
// 1× and the tiled package.
#pragma once
#include <cstdint>
#include <vector>

#include <glm/vec2.hpp>

#include "graph/block_table.h"
#include "graph/cell_tables.h"
#include "graph/street_graph.h"
#include "package/writer.h"

namespace blvd::bake {

struct TileOptions {
  uint32_t nx = 1, ny = 1;  // copies east and north; 1 × 1 is the plain city
  double gap_m = 200;       // between neighbouring copies' bounding boxes
};

struct TileLayout {
  glm::dvec2 step{0, 0};  // east/north shift from one copy to the next, metres
  uint32_t copies = 1;
  uint32_t cells = 0, blocks = 0, vertices = 0, blobs = 0;  // per copy
};

// Replaces g, blocks and tables by the N × M copies and appends the copies'
// blobs to `writer` (translated GLBs: the same Draco bytes under a node
// translation). Every blob in `writer` must belong to the original city.
// Throws core::Error(InvalidArg) for 0 copies or a gap < 0, and
// core::Error(Internal) when a count overflows 32 bits.
TileLayout tileCity(graph::StreetGraph& g, std::vector<graph::BlockRecord>& blocks, graph::CellTables& tables,
                    package::PackageWriter& writer, const TileOptions& opt);

}  // namespace blvd::bake
