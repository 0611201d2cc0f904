// Geometry on the terrain (bake/terrain.h), on analytic ground: a plane tilted
// 10 %, a cone and a bowl. Draped surfaces follow the ground (exactly on a
// plane, within a stated bound on a cone), keep no edge longer than asked and
// no crack (every inner edge has two triangles); a building stands at the
// lowest ground under it, inside its footprint too; the DEM's heights arrive
// in the package's frame.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <utility>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "bake/terrain.h"
#include "core/status.h"

namespace {

using blvd::bake::TerrainHeight;

// A square of ground from (x0, y0) to (x1, y1) (east, north) as two triangles
// at height `lift`, counter-clockwise seen from above.
blvd::geo::MeshData square(double x0, double y0, double x1, double y1, double lift) {
  blvd::geo::MeshData m;
  const double xs[4] = {x0, x1, x1, x0}, ys[4] = {y0, y0, y1, y1};
  for (int i = 0; i < 4; ++i) {
    float p[3];
    blvd::geo::enuToGltf(xs[i], ys[i], lift, p);
    m.positions.insert(m.positions.end(), p, p + 3);
    m.normals.insert(m.normals.end(), {0.f, 1.f, 0.f});
    m.colors.insert(m.colors.end(), {200, 190, 180, 255});
  }
  m.indices = {0, 1, 2, 0, 2, 3};
  return m;
}

glm::dvec2 en(const blvd::geo::MeshData& m, uint32_t v) { return {m.positions[3 * v], -m.positions[3 * v + 2]}; }

// Edges of the mesh with the number of triangles on each.
std::map<std::pair<uint32_t, uint32_t>, int> edges(const blvd::geo::MeshData& m) {
  std::map<std::pair<uint32_t, uint32_t>, int> e;
  for (size_t t = 0; t < m.indices.size(); t += 3)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = m.indices[t + k], b = m.indices[t + (k + 1) % 3];
      ++e[{std::min(a, b), std::max(a, b)}];
    }
  return e;
}

TEST(Terrain, ADrapedSquareFollowsATiltedPlaneWithoutCracks) {
  const TerrainHeight tilted = [](glm::dvec2 p) { return 0.1 * p.x; };  // 10 % up to the east
  blvd::geo::MeshData m = square(0, 0, 100, 100, 0.03);
  blvd::bake::subdivideLongEdges(m, 8.0);
  blvd::bake::drapeOnTerrain(m, tilted);
  ASSERT_GT(m.triangleCount(), 2u * 12 * 12);
  double boundary = 0, area = 0;
  for (const auto& [e, n] : edges(m)) {
    const double l = glm::length(en(m, e.second) - en(m, e.first));
    EXPECT_LE(l, 8.0 + 1e-9);
    ASSERT_LE(n, 2);
    if (n == 1) boundary += l;  // a crack would add inner edges with one triangle
  }
  EXPECT_NEAR(boundary, 400.0, 1e-6);
  for (size_t t = 0; t < m.indices.size(); t += 3) {
    const glm::dvec2 a = en(m, m.indices[t]), b = en(m, m.indices[t + 1]), c = en(m, m.indices[t + 2]);
    const double cross = (b - a).x * (c - a).y - (b - a).y * (c - a).x;
    EXPECT_GT(cross, 0.0);  // still counter-clockwise from above
    area += 0.5 * cross;
  }
  EXPECT_NEAR(area, 100.0 * 100.0, 1e-6);
  const glm::vec3 up = glm::normalize(glm::vec3(-0.1f, 1.f, 0.f));
  for (uint32_t v = 0; v < m.vertexCount(); ++v) {
    EXPECT_NEAR(m.positions[3 * v + 1], 0.03 + 0.1 * en(m, v).x, 1e-4);
    EXPECT_NEAR(m.normals[3 * v], up.x, 1e-4);
    EXPECT_NEAR(m.normals[3 * v + 1], up.y, 1e-4);
  }
}

// A cone 50 m high falling 0.5 m a metre: the draped surface between its
// vertices is linear, the cone is not; with edges of at most 5 m the centroid
// of every triangle away from the summit (10 m) is within 0.2 m of the cone
// (the bound of a linear interpolant, curvature 0.5 / r times the edge squared / 8).
TEST(Terrain, ADrapedSquareStaysNearACone) {
  const TerrainHeight cone = [](glm::dvec2 p) { return std::max(0.0, 50.0 - 0.5 * glm::length(p)); };
  blvd::geo::MeshData m = square(-80, -80, 80, 80, 0.0);
  blvd::bake::subdivideLongEdges(m, 5.0);
  blvd::bake::drapeOnTerrain(m, cone);
  double worst = 0;
  for (size_t t = 0; t < m.indices.size(); t += 3) {
    glm::dvec2 c(0);
    double y = 0;
    for (int k = 0; k < 3; ++k) c += en(m, m.indices[t + k]) / 3.0, y += m.positions[3 * m.indices[t + k] + 1] / 3.0;
    if (glm::length(c) < 10 || glm::length(c) > 95) continue;  // the summit, and the foot's crease at r = 100
    worst = std::max(worst, std::abs(y - cone(c)));
  }
  EXPECT_LT(worst, 0.2);
  std::printf("cone: %zu triangles, worst centroid off the cone %.3f m\n", m.triangleCount(), worst);
}

// The adaptive split on the cone: where the cone bends away from the straight
// edges (it bends everywhere, most near its summit and at its foot),
// conforming (no crack), and fewer triangles than a uniform split to the
// shortest edge.
TEST(Terrain, AdaptiveDrapingSplitsWhereTheGroundBendsWithoutCracks) {
  const TerrainHeight cone = [](glm::dvec2 p) { return std::max(0.0, 50.0 - 0.5 * glm::length(p)); };
  blvd::geo::MeshData m = square(-80, -80, 80, 80, 0.0);
  blvd::bake::DrapeTolerance tol;
  blvd::bake::subdivideForTerrain(m, cone, tol);
  double boundary = 0;
  for (const auto& [e, n] : edges(m)) {
    ASSERT_LE(n, 2);
    const double l = glm::length(en(m, e.second) - en(m, e.first));
    EXPECT_LE(l, tol.max_edge_m + 1e-9);
    if (n == 1) boundary += l;
    // An edge left long enough to split lies on the cone within the tolerance.
    const glm::dvec2 a = en(m, e.first), b = en(m, e.second);
    if (l > tol.min_edge_m) {
      EXPECT_LE(std::abs(cone(0.5 * (a + b)) - 0.5 * (cone(a) + cone(b))), tol.height_m + 1e-9);
    }
  }
  EXPECT_NEAR(boundary, 640.0, 1e-6);
  blvd::geo::MeshData uniform = square(-80, -80, 80, 80, 0.0);
  blvd::bake::subdivideLongEdges(uniform, tol.min_edge_m);
  EXPECT_LT(m.triangleCount(), uniform.triangleCount());
  std::printf("cone, adaptive: %zu triangles (uniform to %.0f m: %zu)\n", m.triangleCount(), tol.min_edge_m,
              uniform.triangleCount());
}

TEST(Terrain, ABuildingStandsAtTheLowestGroundUnderIt) {
  blvd::bake::Polygon2 lot;
  lot.outer.pts = {{10, -10}, {30, -10}, {30, 10}, {10, 10}};
  const TerrainHeight tilted = [](glm::dvec2 p) { return 0.1 * p.x; };
  EXPECT_NEAR(blvd::bake::lowestUnder({lot}, tilted, 30.0), 1.0, 1e-9);  // its west wall
  // A bowl: the lowest ground is inside the footprint, not at its corners.
  blvd::bake::Polygon2 over;
  over.outer.pts = {{-20, -20}, {20, -20}, {20, 20}, {-20, 20}};
  const TerrainHeight bowl = [](glm::dvec2 p) { return 5.0 + glm::dot(p, p) / 100.0; };
  EXPECT_NEAR(blvd::bake::lowestUnder({over}, bowl, 100.0), 13.0, 1e-9);  // corners only: no grid point inside
  EXPECT_LT(blvd::bake::lowestUnder({over}, bowl, 5.0), 5.2);            // 2.5 m from the centre
  // An inner ring (a courtyard) is not under the building.
  over.inners.push_back(blvd::bake::Ring{{{-10, -10}, {10, -10}, {10, 10}, {-10, 10}}});
  EXPECT_GT(blvd::bake::lowestUnder({over}, bowl, 5.0), 6.0);
  blvd::geo::MeshData wall = square(0, 0, 1, 1, 0.0);
  blvd::bake::raise(wall, 13.0);
  for (uint32_t v = 0; v < wall.vertexCount(); ++v) EXPECT_FLOAT_EQ(wall.positions[3 * v + 1], 13.0f);
}

// The DEM's heights in the frame: a tile of a plane (metres = 1000 x the
// longitude's fraction), the frame's origin height subtracted.
TEST(Terrain, HeightsFromTheDemAreInThePackagesFrame) {
  blvd::bake::DemTile t;
  t.lat0 = 43, t.lon0 = 7, t.n = 1201, t.source = "plane";
  t.h.resize(size_t(t.n) * t.n);
  for (int r = 0; r < t.n; ++r)
    for (int c = 0; c < t.n; ++c) t.h[size_t(r) * t.n + c] = float(1000.0 * c / (t.n - 1));
  blvd::bake::Dem dem;
  dem.addTile(std::move(t));
  const blvd::geo::LocalFrame frame(43.5, 7.5, 100.0);
  const TerrainHeight h = blvd::bake::demTerrain(dem, frame);
  EXPECT_NEAR(h({0, 0}), 500.0 - 100.0, 1e-3);
  // 1 km east: the longitude grows by 1 / (111.32 km x cos 43.5°).
  EXPECT_NEAR(h({1000, 0}), 400.0 + 1000.0 / (111320.0 * std::cos(43.5 * M_PI / 180.0)) * 1000.0, 0.5);
  EXPECT_THROW(h({0, 100000}), blvd::core::Error);  // past the tile: the bake checks coverage first
}

}  // namespace
