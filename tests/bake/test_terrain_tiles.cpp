// The terrain's quadtree tiles (TERR): the tree's order, the section's bytes
// and what a reader refuses, the heights' 16-bit steps, and the tiles the
// bake builds on analytic ground: exact on a plane 10 % steep, within their
// stated error on a cone, errors that never grow down the tree, and the
// margin the DEM does not cover at the fill height.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "bake/terrain_tiles.h"
#include "core/status.h"
#include "graph/terrain_table.h"

namespace blvd {
namespace {

using graph::TerrainLayout;
using graph::TerrainRecord;
using graph::TerrainTile;

TEST(TerrainTable, TileOrderRoundTripsWithChildrenAndParents) {
  EXPECT_EQ(graph::terrainFirstOfLevel(0), 0u);
  EXPECT_EQ(graph::terrainFirstOfLevel(1), 1u);
  EXPECT_EQ(graph::terrainFirstOfLevel(3), 21u);
  for (uint32_t i = 0; i < graph::terrainFirstOfLevel(6); ++i) {
    const TerrainTile t = graph::terrainTileAt(i);
    ASSERT_EQ(graph::terrainIndex(t), i);
    ASSERT_LT(t.x, 1u << t.level);
    ASSERT_LT(t.y, 1u << t.level);
    if (t.level + 1 < 6)
      for (uint32_t k = 0; k < 4; ++k) {
        const uint32_t c = graph::terrainChild(i, k);
        const TerrainTile ct = graph::terrainTileAt(c);
        EXPECT_EQ(ct.level, t.level + 1);
        EXPECT_EQ(ct.x, 2 * t.x + (k & 1));
        EXPECT_EQ(ct.y, 2 * t.y + (k >> 1));
        EXPECT_EQ(graph::terrainParent(c), i);
      }
  }
}

TerrainLayout smallLayout() {
  TerrainLayout l;
  l.grid = 5, l.levels = 2, l.west = -100, l.south = 50, l.size = 400;
  l.base_m = -2, l.step_m = 0.01f, l.level_error_m[0] = 1.5f, l.level_error_m[1] = 1.f;
  return l;
}

std::vector<TerrainRecord> records(uint32_t n) {
  std::vector<TerrainRecord> r(n);
  for (uint32_t i = 0; i < n; ++i) r[i] = TerrainRecord{i, 1.5f, -2.f, 30.f};
  return r;
}

std::string parseError(const std::vector<uint8_t>& b) {
  try {
    graph::parseTerrainHeader(b.data(), b.size(), 1000);
  } catch (const core::Error& e) {
    EXPECT_EQ(e.status(), core::Status::Corrupt);
    return e.what();
  }
  return {};
}

TEST(TerrainTable, TheSectionRoundTripsAndABadOneIsNamedWithItsOffset) {
  const TerrainLayout l = smallLayout();
  const std::vector<uint8_t> b = graph::serializeTerrain(l, records(5));
  ASSERT_EQ(b.size(), graph::kTerrainHeaderBytes + 5 * graph::kTerrainRecordBytes);
  const TerrainLayout back = graph::parseTerrainHeader(b.data(), b.size(), 0);
  EXPECT_EQ(back.grid, 5u);
  EXPECT_EQ(back.levels, 2u);
  EXPECT_EQ(back.west, -100.0);
  EXPECT_EQ(back.south, 50.0);
  EXPECT_EQ(back.size, 400.0);
  EXPECT_EQ(back.tileSize(1), 200.0);
  EXPECT_EQ(back.base_m, -2.f);
  EXPECT_EQ(back.step_m, 0.01f);
  EXPECT_EQ(back.level_error_m[1], 1.f);
  EXPECT_EQ(back.level_error_m[2], 0.f);
  TerrainRecord r;
  EXPECT_EQ(graph::parseTerrainRecord(b.data() + graph::kTerrainHeaderBytes + 3 * 16, 5, r), "");
  EXPECT_EQ(r.blob, 3u);
  EXPECT_EQ(r.error_m, 1.5f);
  EXPECT_NE(graph::parseTerrainRecord(b.data() + graph::kTerrainHeaderBytes + 3 * 16, 3, r).find("blob 3 past"),
            std::string::npos);

  std::vector<uint8_t> bad = b;
  bad[0] = 9;
  EXPECT_NE(parseError(bad).find("unknown version 9"), std::string::npos) << parseError(bad);
  EXPECT_NE(parseError(bad).find("offset 1000"), std::string::npos) << parseError(bad);
  bad = b;
  bad[4] = 200;  // grid
  EXPECT_NE(parseError(bad).find("grid 200"), std::string::npos) << parseError(bad);
  bad = b;
  bad[12] = 4;  // record count
  EXPECT_NE(parseError(bad).find("4 records for a tree of 5"), std::string::npos) << parseError(bad);
  bad = b;
  bad.resize(b.size() - 1);
  EXPECT_NE(parseError(bad).find("truncated"), std::string::npos) << parseError(bad);
  bad = b;
  const float zero = 0;
  std::memcpy(bad.data() + 44, &zero, 4);  // step
  EXPECT_NE(parseError(bad).find("height steps"), std::string::npos) << parseError(bad);
  bad = b;
  const float one = 1;
  std::memcpy(bad.data() + 48 + 4 * 5, &one, 4);  // an error for a level the tree does not have
  EXPECT_NE(parseError(bad).find("level 5"), std::string::npos) << parseError(bad);
  bad = b;
  const double nan = std::nan("");
  std::memcpy(bad.data() + 32, &nan, 8);  // size
  EXPECT_NE(parseError(bad).find("extent"), std::string::npos) << parseError(bad);
  EXPECT_NE(parseError(std::vector<uint8_t>(b.begin(), b.begin() + 10)).find("truncated"), std::string::npos);

  EXPECT_THROW(graph::serializeTerrain(l, records(4)), core::Error);
  std::vector<TerrainRecord> flipped = records(5);
  flipped[2].min_m = 40.f;
  EXPECT_THROW(graph::serializeTerrain(l, flipped), core::Error);
}

TEST(TerrainTable, HeightsKeepTheirSixteenBitSteps) {
  std::vector<float> h(9 * 9);
  for (size_t i = 0; i < h.size(); ++i) h[i] = -12.f + 0.731f * float(i);
  TerrainLayout l;
  l.grid = 9, l.base_m = -12.f, l.step_m = (h.back() - h.front()) / 65535.f;
  const std::vector<uint8_t> b = graph::encodeTerrainHeights(h.data(), l);
  ASSERT_EQ(b.size(), 2u * 81);
  std::vector<float> back(81);
  ASSERT_TRUE(graph::decodeTerrainHeights(b.data(), b.size(), l, back.data()));
  for (size_t i = 0; i < h.size(); ++i) EXPECT_NEAR(back[i], h[i], 0.5 * l.step_m + 1e-4) << i;
  EXPECT_FALSE(graph::decodeTerrainHeights(b.data(), b.size() - 2, l, back.data()));
}

// The largest difference between the tile's surface and `f` at random points
// of each tile, less its stated error (positive: the error understates).
template <class F>
double worstUnderstatement(const bake::TerrainTileSet& set, F f, uint32_t samples) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u01(0, 1);
  const uint32_t g = set.layout.grid;
  std::vector<float> h(size_t(g) * g);
  double worst = -1e9;
  for (uint32_t i = 0; i < set.records.size(); ++i) {
    const TerrainRecord& r = set.records[i];
    EXPECT_TRUE(graph::decodeTerrainHeights(set.blobs[r.blob].data(), set.blobs[r.blob].size(), set.layout, h.data()));
    const TerrainTile t = graph::terrainTileAt(i);
    const double ts = set.layout.tileSize(t.level);
    for (uint32_t k = 0; k < samples; ++k) {
      const double a = u01(rng), b = u01(rng);
      const double e = set.layout.west + (t.x + a) * ts, n = set.layout.south + (t.y + b) * ts;
      const double surface = bake::terrainTileSurface(h.data(), g, a * (g - 1), b * (g - 1));
      worst = std::max(worst, std::abs(surface - f(e, n)) - r.error_m);
    }
  }
  return worst;
}

TEST(TerrainTiles, OnAPlaneEveryTileIsExactButForItsRounding) {
  auto plane = [](double e, double n) { return 5.0 + 0.1 * e - 0.03 * n; };
  bake::TerrainTileOptions o;
  o.grid = 9, o.spacing_m = 25, o.margin_m = 100, o.error_step_m = 10;
  const bake::TerrainTileSet set =
      bake::buildTerrainTiles([&](glm::dvec2 p) { return plane(p.x, p.y); }, {0, 0}, {600, 300}, o);
  // The root: the box's 600 m plus 100 m a side, around its centre.
  EXPECT_DOUBLE_EQ(set.layout.size, 800.0);
  EXPECT_DOUBLE_EQ(set.layout.west, -100.0);
  EXPECT_DOUBLE_EQ(set.layout.south, -250.0);
  // 800 / 8 = 100 m at level 0; 25 m at level 2: three levels.
  EXPECT_EQ(set.layout.levels, 3u);
  ASSERT_EQ(set.records.size(), 21u);
  EXPECT_EQ(set.uncovered, 0u);
  for (const TerrainRecord& r : set.records) {
    EXPECT_LE(r.error_m, set.layout.step_m);  // half a step of rounding at each corner
    EXPECT_LT(r.min_m, r.max_m);
  }
  for (uint32_t k = 0; k < 3; ++k) EXPECT_LE(set.layout.level_error_m[k], set.layout.step_m);
  EXPECT_LT(worstUnderstatement(set, plane, 200), 1e-3);
}

TEST(TerrainTiles, OnAConeTheErrorBoundsTheSurfaceAndNeverGrowsDownTheTree) {
  auto cone = [](double e, double n) { return std::max(0.0, 300.0 - 0.6 * std::hypot(e - 400, n - 350)); };
  bake::TerrainTileOptions o;
  o.grid = 9, o.spacing_m = 20, o.margin_m = 0, o.error_step_m = 4;
  const bake::TerrainTileSet set =
      bake::buildTerrainTiles([&](glm::dvec2 p) { return cone(p.x, p.y); }, {0, 0}, {800, 800}, o);
  EXPECT_EQ(set.layout.levels, 4u);  // 100, 50, 25, 12.5 m
  for (uint32_t i = 1; i < set.records.size(); ++i)
    ASSERT_GE(set.records[graph::terrainParent(i)].error_m, set.records[i].error_m) << "tile " << i;
  EXPECT_GT(set.records[0].error_m, 10.f);  // the root cannot hold the cone's tip
  EXPECT_LT(set.records.back().error_m, set.records[0].error_m);
  // Each level's error is its tiles' largest, and shrinks level by level.
  for (uint32_t i = 0; i < set.records.size(); ++i)
    EXPECT_LE(set.records[i].error_m, set.layout.level_error_m[graph::terrainTileAt(i).level]);
  for (uint32_t k = 1; k < set.layout.levels; ++k)
    EXPECT_LE(set.layout.level_error_m[k], set.layout.level_error_m[k - 1]) << "level " << k;
  // Between the points it was measured at (a point is at most half a
  // diagonal of the step from one), the difference can change by the cone's
  // slope (0.6) plus the surface's (a triangle's at most √2 times that).
  const double between = (0.6 + 0.6 * std::sqrt(2.0)) * o.error_step_m * std::sqrt(0.5);
  EXPECT_LT(worstUnderstatement(set, cone, 300), between);
}

TEST(TerrainTiles, GroundTheDemDoesNotCoverIsAtTheFillHeight) {
  bake::TerrainTileOptions o;
  o.grid = 5, o.spacing_m = 100, o.margin_m = 200, o.fill_m = -7;
  const bake::TerrainTileSet set = bake::buildTerrainTiles(
      [](glm::dvec2 p) { return p.x < 0 ? std::nan("") : 20.0; }, {0, 0}, {100, 100}, o);
  EXPECT_GT(set.uncovered, 0u);
  EXPECT_FLOAT_EQ(set.records[0].min_m, -7.f);
  EXPECT_FLOAT_EQ(set.records[0].max_m, 20.f);
  EXPECT_THROW(bake::buildTerrainTiles([](glm::dvec2) { return 0.0; }, {0, 0}, {1, 1}, bake::TerrainTileOptions{1}),
               core::Error);
}

}  // namespace
}  // namespace blvd
