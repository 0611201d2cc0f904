#include "bake/terrain_tiles.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/status.h"

namespace blvd::bake {
namespace {

using graph::TerrainLayout;
using graph::TerrainRecord;

TerrainLayout layoutFor(glm::dvec2 lo, glm::dvec2 hi, const TerrainTileOptions& opt) {
  if (opt.grid < graph::kTerrainMinGrid || opt.grid > graph::kTerrainMaxGrid || !(opt.spacing_m > 0) ||
      !(opt.margin_m >= 0) || !(opt.error_step_m > 0) || !(hi.x >= lo.x && hi.y >= lo.y))
    throw core::Error(core::Status::InvalidArg, "terrain tiles: a grid of 2..129, a positive spacing and error step, "
                                                "a margin of 0 or more and a box are needed");
  TerrainLayout l;
  l.grid = opt.grid;
  l.size = std::max({hi.x - lo.x, hi.y - lo.y, 1.0}) + 2 * opt.margin_m;
  l.west = 0.5 * (lo.x + hi.x) - 0.5 * l.size;
  l.south = 0.5 * (lo.y + hi.y) - 0.5 * l.size;
  l.levels = 1;
  while (l.levels < graph::kTerrainMaxLevels && l.tileSize(l.levels - 1) / (opt.grid - 1) > opt.spacing_m) ++l.levels;
  return l;
}

// The terrain at points `step` apart over the root tile, the truth each tile's
// error is measured against.
struct Truth {
  double step = 0;
  uint32_t n = 0;  // points per side
  std::vector<float> h;
};

Truth sampleTruth(const TerrainHeight& height, const TerrainLayout& l, const TerrainTileOptions& opt) {
  Truth t;
  t.step = std::max(opt.error_step_m, l.size / 4096);
  t.n = uint32_t(std::ceil(l.size / t.step)) + 1;
  t.h.resize(size_t(t.n) * t.n);
  for (uint32_t j = 0; j < t.n; ++j)
    for (uint32_t i = 0; i < t.n; ++i) {
      const double z = height({l.west + std::min(i * t.step, l.size), l.south + std::min(j * t.step, l.size)});
      t.h[size_t(j) * t.n + i] = float(std::isnan(z) ? opt.fill_m : z);
    }
  return t;
}

// A tile's heights at its grid points (rows south to north).
std::vector<float> tileHeights(const TerrainHeight& height, const TerrainLayout& l, graph::TerrainTile tile,
                               double fill_m, uint64_t& uncovered) {
  const uint32_t g = l.grid;
  const double ts = l.tileSize(tile.level), x0 = l.west + tile.x * ts, y0 = l.south + tile.y * ts;
  std::vector<float> h(size_t(g) * g);
  for (uint32_t j = 0; j < g; ++j)
    for (uint32_t i = 0; i < g; ++i) {
      double z = height({x0 + ts * i / (g - 1), y0 + ts * j / (g - 1)});
      if (std::isnan(z)) z = fill_m, ++uncovered;
      h[size_t(j) * g + i] = float(z);
    }
  return h;
}

// The most the tile's drawn surface departs from the truth inside it.
float tileError(const float* heights, const TerrainLayout& l, graph::TerrainTile tile, const Truth& truth) {
  const double ts = l.tileSize(tile.level), x0 = tile.x * ts, y0 = tile.y * ts;
  const auto first = uint32_t(std::ceil(x0 / truth.step)), last = std::min(truth.n - 1, uint32_t((x0 + ts) / truth.step));
  const auto jfirst = uint32_t(std::ceil(y0 / truth.step)), jlast = std::min(truth.n - 1, uint32_t((y0 + ts) / truth.step));
  const double per = (l.grid - 1) / ts;
  double err = 0;
  for (uint32_t j = jfirst; j <= jlast; ++j)
    for (uint32_t i = first; i <= last; ++i) {
      const double u = std::clamp((std::min(i * truth.step, l.size) - x0) * per, 0.0, double(l.grid - 1));
      const double v = std::clamp((std::min(j * truth.step, l.size) - y0) * per, 0.0, double(l.grid - 1));
      err = std::max(err, std::abs(terrainTileSurface(heights, l.grid, u, v) - truth.h[size_t(j) * truth.n + i]));
    }
  return float(err);
}

}  // namespace

double terrainTileSurface(const float* h, uint32_t grid, double u, double v) {
  const auto i = uint32_t(std::min(std::floor(u), double(grid - 2)));
  const auto j = uint32_t(std::min(std::floor(v), double(grid - 2)));
  const double a = u - i, b = v - j;
  const double h00 = h[size_t(j) * grid + i], h10 = h[size_t(j) * grid + i + 1];
  const double h01 = h[size_t(j + 1) * grid + i], h11 = h[size_t(j + 1) * grid + i + 1];
  return a >= b ? h00 + a * (h10 - h00) + b * (h11 - h10) : h00 + b * (h01 - h00) + a * (h11 - h01);
}

TerrainTileSet buildTerrainTiles(const TerrainHeight& height, glm::dvec2 lo, glm::dvec2 hi,
                                 const TerrainTileOptions& opt) {
  TerrainTileSet out;
  out.layout = layoutFor(lo, hi, opt);
  const TerrainLayout& l = out.layout;
  const Truth truth = sampleTruth(height, l, opt);
  std::vector<std::vector<float>> heights(l.tiles());
  float low = std::numeric_limits<float>::infinity(), high = -low;
  for (uint32_t i = 0; i < l.tiles(); ++i) {
    heights[i] = tileHeights(height, l, graph::terrainTileAt(i), opt.fill_m, out.uncovered);
    for (float h : heights[i]) low = std::min(low, h), high = std::max(high, h);
  }
  out.layout.base_m = low;
  out.layout.step_m = std::max((high - low) / 65535.0f, 1e-3f);
  out.records.resize(l.tiles());
  out.blobs.resize(l.tiles());
  std::vector<float> decoded(size_t(l.grid) * l.grid);
  for (uint32_t i = 0; i < l.tiles(); ++i) {
    TerrainRecord& r = out.records[i];
    r.blob = i;
    r.min_m = *std::min_element(heights[i].begin(), heights[i].end());
    r.max_m = *std::max_element(heights[i].begin(), heights[i].end());
    out.blobs[i] = graph::encodeTerrainHeights(heights[i].data(), l);
    graph::decodeTerrainHeights(out.blobs[i].data(), out.blobs[i].size(), l, decoded.data());
    r.error_m = tileError(decoded.data(), l, graph::terrainTileAt(i), truth);
  }
  for (uint32_t i = uint32_t(l.tiles()); i-- > 1;) {  // children before parents
    float& parent = out.records[graph::terrainParent(i)].error_m;
    parent = std::max(parent, out.records[i].error_m);
  }
  for (uint32_t i = 0; i < l.tiles(); ++i) {
    float& e = out.layout.level_error_m[graph::terrainTileAt(i).level];
    e = std::max(e, out.records[i].error_m);
  }
  return out;
}

}  // namespace blvd::bake
