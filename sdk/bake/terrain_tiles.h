// The terrain beyond the blocks: the TERR section's quadtree of height tiles
// (graph/terrain_table.h) built from the DEM over the city's box and a margin
// around it.
//
// The rules:
// - The root tile is the square around the city's box grown by `margin_m` on
//   every side; levels are added until the finest tiles' sample spacing is at
//   most `spacing_m` (about SRTM3's: finer tiles would only interpolate).
// - A tile's heights are the terrain's at its grid points, in 16-bit steps of
//   one size over the whole tree (its range / 65535, at least a millimetre).
// - Its geometric error is the most its surface (two triangles a grid square,
//   split along the south-west to north-east diagonal, as the runtime draws
//   it), with the 16-bit rounding of its heights, departs from the terrain at
//   points `error_step_m` apart and at the terrain's own samples there; then
//   raised to its children's largest, so that no tile is more exact than a
//   tile below it (a parent refined is never worse).
// - Where the DEM has no height (outside every tile given) the ground is
//   `fill_m` (the sea's level in the package's frame), counted in `uncovered`.
#pragma once
#include <cstdint>
#include <vector>

#include <glm/vec2.hpp>

#include "bake/terrain.h"
#include "graph/terrain_table.h"

namespace blvd::bake {

struct TerrainTileOptions {
  uint32_t grid = 17;           // heights per tile side: 16 × 16 squares, 512 triangles
  double spacing_m = 60.0;      // the finest level's spacing at most this
  double margin_m = 3000.0;     // around the city's box: the runtime's default far distance
  double error_step_m = 30.0;   // where the error is measured: a third of SRTM3's spacing
  double fill_m = 0.0;          // the height where the DEM has none
};

struct TerrainTileSet {
  graph::TerrainLayout layout;
  std::vector<graph::TerrainRecord> records;  // blob: the index into `blobs`
  std::vector<std::vector<uint8_t>> blobs;
  uint64_t uncovered = 0;       // grid points without a DEM height
};

// `height` gives NaN where the DEM has no data. `lo`, `hi`: the city's box
// (local east/north metres).
TerrainTileSet buildTerrainTiles(const TerrainHeight& height, glm::dvec2 lo, glm::dvec2 hi,
                                 const TerrainTileOptions& opt = TerrainTileOptions());

// The surface a tile draws at (u, v) in [0, grid − 1]² grid steps from its
// south-west corner: two triangles a square, split south-west to north-east.
double terrainTileSurface(const float* heights, uint32_t grid, double u, double v);

}  // namespace blvd::bake
