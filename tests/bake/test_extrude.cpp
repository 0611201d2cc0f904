// Building extrusion: counts, normals, winding and facing of walls, roof and
// bottom cap, in glTF axes (x east, y up, z south).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "bake/extrude.h"

namespace blvd::bake {
namespace {

const uint8_t kWall[4] = {200, 180, 150, 255};
const uint8_t kRoof[4] = {120, 100, 90, 255};

Ring rect(double x0, double y0, double x1, double y1) {
  return Ring{{{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}};
}

struct Tri {
  glm::dvec3 p[3];
  glm::dvec3 n;  // normal of the first vertex (faces are flat-shaded)
  const uint8_t* rgba;
  glm::dvec3 centroid() const { return (p[0] + p[1] + p[2]) / 3.0; }
  glm::dvec2 centroidEn() const { return {centroid().x, -centroid().z}; }
  bool isWall() const { return std::abs(n.y) < 0.5; }
  bool isRoof() const { return n.y > 0.5; }
  bool isBottom() const { return n.y < -0.5; }
};

std::vector<Tri> triangles(const geo::MeshData& m) {
  std::vector<Tri> out;
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    Tri tri;
    for (int k = 0; k < 3; ++k) {
      const uint32_t i = m.indices[3 * t + k];
      tri.p[k] = {m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]};
    }
    const uint32_t i0 = m.indices[3 * t];
    tri.n = {m.normals[3 * i0], m.normals[3 * i0 + 1], m.normals[3 * i0 + 2]};
    tri.rgba = &m.colors[4 * i0];
    out.push_back(tri);
  }
  return out;
}

// Whether an east/north point lies under the roof (inside a roof triangle).
bool underRoof(const std::vector<Tri>& tris, glm::dvec2 q) {
  for (const Tri& t : tris) {
    if (!t.isRoof()) continue;
    bool pos = true;
    for (int k = 0; k < 3; ++k) {
      const glm::dvec2 a(t.p[k].x, -t.p[k].z), b(t.p[(k + 1) % 3].x, -t.p[(k + 1) % 3].z);
      const glm::dvec2 d = b - a, r = q - a;
      pos = pos && d.x * r.y - d.y * r.x > 0.0;
    }
    if (pos) return true;
  }
  return false;
}

// Checks shared by every extrusion: well-formed arrays, unit normals equal
// across each (flat) face, counter-clockwise winding seen from the side the
// normal points to, and walls with the solid behind them and air in front.
void expectValid(const geo::MeshData& m) {
  ASSERT_EQ(m.positions.size(), m.normals.size());
  ASSERT_EQ(m.colors.size() / 4, m.positions.size() / 3);
  ASSERT_EQ(m.indices.size() % 3, 0u);
  for (uint32_t i : m.indices) ASSERT_LT(i, m.vertexCount());
  for (size_t v = 0; v < m.vertexCount(); ++v) {
    const glm::dvec3 n(m.normals[3 * v], m.normals[3 * v + 1], m.normals[3 * v + 2]);
    EXPECT_NEAR(glm::length(n), 1.0, 1e-6);
  }
  const std::vector<Tri> tris = triangles(m);
  for (const Tri& t : tris) {
    const glm::dvec3 geometric = glm::cross(t.p[1] - t.p[0], t.p[2] - t.p[0]);
    EXPECT_GT(glm::dot(geometric, t.n), 0.0) << "winding disagrees with normal";
    if (!t.isWall()) continue;
    EXPECT_NEAR(t.n.y, 0.0, 1e-6);
    const glm::dvec2 n(t.n.x, -t.n.z);
    EXPECT_FALSE(underRoof(tris, t.centroidEn() + 0.01 * n)) << "wall faces into the solid";
    EXPECT_TRUE(underRoof(tris, t.centroidEn() - 0.01 * n)) << "no solid behind the wall";
  }
}

size_t count(const std::vector<Tri>& tris, bool (Tri::*pred)() const) {
  size_t c = 0;
  for (const Tri& t : tris) c += (t.*pred)() ? 1 : 0;
  return c;
}

TEST(Extrude, Box) {
  geo::MeshData m;
  std::string why;
  ASSERT_TRUE(extrudeBuilding({rect(0, 0, 10, 6), {}}, 0.0, 10.0, kWall, kRoof, m, why)) << why;
  expectValid(m);
  EXPECT_EQ(m.triangleCount(), 4u * 2u + 2u);
  EXPECT_EQ(m.vertexCount(), 4u * 4u + 4u);  // walls do not share vertices
  const std::vector<Tri> tris = triangles(m);
  EXPECT_EQ(count(tris, &Tri::isWall), 8u);
  EXPECT_EQ(count(tris, &Tri::isRoof), 2u);
  EXPECT_EQ(count(tris, &Tri::isBottom), 0u);
  const glm::dvec3 centre(5.0, 5.0, -3.0);  // footprint centroid in glTF axes
  for (const Tri& t : tris) {
    if (t.isWall()) {
      glm::dvec3 out = t.centroid() - centre;
      out.y = 0.0;
      EXPECT_GT(glm::dot(t.n, out), 0.0);
      EXPECT_EQ(std::vector<uint8_t>(t.rgba, t.rgba + 4), std::vector<uint8_t>(kWall, kWall + 4));
      for (const glm::dvec3& p : t.p) EXPECT_TRUE(p.y == 0.0 || p.y == 10.0);
    } else {
      for (const glm::dvec3& p : t.p) EXPECT_EQ(p.y, 10.0);
      EXPECT_EQ(std::vector<uint8_t>(t.rgba, t.rgba + 4), std::vector<uint8_t>(kRoof, kRoof + 4));
    }
  }
}

TEST(Extrude, NorthIsMinusZ) {
  geo::MeshData m;
  std::string why;
  ASSERT_TRUE(extrudeBuilding({rect(0, 100, 1, 101), {}}, 0.0, 3.0, kWall, kRoof, m, why));
  for (size_t v = 0; v < m.vertexCount(); ++v) {
    EXPECT_GE(m.positions[3 * v + 2], -101.0f);
    EXPECT_LE(m.positions[3 * v + 2], -100.0f);
  }
}

TEST(Extrude, ClockwiseFootprintStillFacesOutward) {
  Ring r = rect(0, 0, 10, 6);
  std::reverse(r.pts.begin(), r.pts.end());
  geo::MeshData m;
  std::string why;
  ASSERT_TRUE(extrudeBuilding({r, {}}, 0.0, 10.0, kWall, kRoof, m, why)) << why;
  expectValid(m);
  EXPECT_EQ(m.triangleCount(), 10u);
}

TEST(Extrude, RaisedPartHasBottomCap) {
  geo::MeshData m;
  std::string why;
  ASSERT_TRUE(extrudeBuilding({rect(0, 0, 10, 6), {}}, 3.0, 10.0, kWall, kRoof, m, why)) << why;
  expectValid(m);
  EXPECT_EQ(m.triangleCount(), 12u);
  const std::vector<Tri> tris = triangles(m);
  EXPECT_EQ(count(tris, &Tri::isBottom), 2u);
  for (const Tri& t : tris) {
    for (const glm::dvec3& p : t.p) {
      if (t.isBottom()) {
        EXPECT_EQ(p.y, 3.0);
      }
      EXPECT_GE(p.y, 3.0);
    }
  }
}

TEST(Extrude, CourtyardWallsFaceTheCourtyard) {
  Polygon2 fp{rect(0, 0, 20, 20), {rect(6, 6, 14, 14)}};
  geo::MeshData m;
  std::string why;
  ASSERT_TRUE(extrudeBuilding(fp, 0.0, 12.0, kWall, kRoof, m, why)) << why;
  expectValid(m);
  const std::vector<Tri> tris = triangles(m);
  EXPECT_EQ(count(tris, &Tri::isWall), 16u);
  size_t inner = 0;
  for (const Tri& t : tris) {
    if (!t.isWall()) continue;
    const glm::dvec2 c = t.centroidEn();
    if (c.x < 6 - 1e-6 || c.x > 14 + 1e-6 || c.y < 6 - 1e-6 || c.y > 14 + 1e-6) continue;
    ++inner;
    const glm::dvec2 to_court = glm::dvec2(10, 10) - c;
    EXPECT_GT(glm::dot(glm::dvec2(t.n.x, -t.n.z), to_court), 0.0);
  }
  EXPECT_EQ(inner, 8u);
}

TEST(Extrude, CollinearNodesShareOneWall) {
  // Nodes where neighbours touch the facade do not split the wall.
  Ring r{{{0, 0}, {3, 0}, {5, 0}, {10, 0}, {10, 6}, {4, 6}, {0, 6}, {0, 2}}};
  geo::MeshData m;
  std::string why;
  ASSERT_TRUE(extrudeBuilding({r, {}}, 0.0, 10.0, kWall, kRoof, m, why)) << why;
  expectValid(m);
  EXPECT_EQ(count(triangles(m), &Tri::isWall), 8u);
}

TEST(Extrude, RoundTowerKeepsItsShape) {
  constexpr double kPi = 3.14159265358979323846;
  Ring r;
  for (int i = 0; i < 64; ++i) {
    r.pts.push_back(8.0 * glm::dvec2(std::cos(2 * kPi * i / 64), std::sin(2 * kPi * i / 64)));
  }
  geo::MeshData m;
  std::string why;
  ASSERT_TRUE(extrudeBuilding({r, {}}, 0.0, 30.0, kWall, kRoof, m, why)) << why;
  expectValid(m);
  EXPECT_EQ(count(triangles(m), &Tri::isWall), 2u * 64u);
}

TEST(Extrude, DirtyFootprints) {
  const Polygon2 cases[] = {
      // figure 8 touching at (1,1)
      {Ring{{{0, 0}, {1, 0}, {1, 1}, {2, 1}, {2, 2}, {1, 2}, {1, 1}, {0, 1}}}, {}},
      // bow-tie
      {Ring{{{0, 0}, {2, 2}, {2, 0}, {0, 2}}}, {}},
      // two courtyards sharing an edge: no wall between them
      {rect(0, 0, 10, 10), {rect(2, 2, 5, 8), rect(5, 2, 8, 8)}},
      // repeated nodes and closing node
      {Ring{{{0, 0}, {0, 0}, {4, 0}, {4, 3}, {4, 3}, {0, 3}, {0, 0}}}, {}},
  };
  const size_t walls[] = {8, 6, 8, 4};
  for (size_t i = 0; i < std::size(cases); ++i) {
    geo::MeshData m;
    std::string why;
    ASSERT_TRUE(extrudeBuilding(cases[i], 0.0, 5.0, kWall, kRoof, m, why)) << i << ": " << why;
    SCOPED_TRACE(i);
    expectValid(m);
    EXPECT_EQ(count(triangles(m), &Tri::isWall), 2u * walls[i]);
  }
}

TEST(Extrude, AppendsAfterExistingGeometry) {
  geo::MeshData m;
  std::string why;
  ASSERT_TRUE(extrudeBuilding({rect(0, 0, 1, 1), {}}, 0.0, 3.0, kWall, kRoof, m, why));
  const size_t v0 = m.vertexCount(), t0 = m.triangleCount();
  ASSERT_TRUE(extrudeBuilding({rect(5, 5, 6, 6), {}}, 0.0, 3.0, kWall, kRoof, m, why));
  expectValid(m);
  EXPECT_EQ(m.vertexCount(), 2 * v0);
  for (size_t i = 3 * t0; i < m.indices.size(); ++i) EXPECT_GE(m.indices[i], v0);
}

TEST(Extrude, UnusableInputAppendsNothing) {
  geo::MeshData m;
  std::string why;
  ASSERT_TRUE(extrudeBuilding({rect(0, 0, 1, 1), {}}, 0.0, 3.0, kWall, kRoof, m, why));
  const geo::MeshData before = m;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  struct Case {
    Polygon2 fp;
    double lo, hi;
  };
  const Case cases[] = {
      {{Ring{{{0, 0}, {1, 1}, {2, 2}}}, {}}, 0.0, 3.0},  // collinear
      {{Ring{{{0, 0}, {1, 1}}}, {}}, 0.0, 3.0},          // two points
      {{rect(0, 0, 1, 1), {}}, 3.0, 3.0},                // no height
      {{rect(0, 0, 1, 1), {}}, 5.0, 3.0},                // upside down
      {{rect(0, 0, 1, 1), {}}, 0.0, nan},
      {{rect(0, nan, 1, 1), {}}, 0.0, 3.0},
  };
  for (const Case& c : cases) {
    why.clear();
    EXPECT_FALSE(extrudeBuilding(c.fp, c.lo, c.hi, kWall, kRoof, m, why));
    EXPECT_FALSE(why.empty());
    EXPECT_EQ(m.positions, before.positions);
    EXPECT_EQ(m.indices, before.indices);
  }
}

TEST(BuildingColour, DeterministicAndVaried) {
  std::set<uint32_t> seen;
  for (uint64_t id = 1; id <= 200; ++id) {
    uint8_t a[4], b[4];
    buildingColour(id, a);
    buildingColour(id, b);
    EXPECT_EQ(std::vector<uint8_t>(a, a + 4), std::vector<uint8_t>(b, b + 4));
    EXPECT_EQ(a[3], 255);
    // Pale facades: no channel darker than a mid ochre.
    for (int k = 0; k < 3; ++k) EXPECT_GE(a[k], 0x50);
    seen.insert((uint32_t(a[0]) << 16) | (uint32_t(a[1]) << 8) | a[2]);
    uint8_t roof[4];
    roofColour(a, roof);
    EXPECT_LT(roof[0] + roof[1] + roof[2], a[0] + a[1] + a[2]);
    EXPECT_EQ(roof[3], a[3]);
  }
  EXPECT_GT(seen.size(), 20u);
}

}  // namespace
}  // namespace blvd::bake
