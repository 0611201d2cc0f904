// Triangulation of dirty polygons: every case OSM footprints are known to
// contain, plus invalid input that must fail cleanly.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <stdexcept>
#include <utility>

#include <glm/geometric.hpp>

#include "bake/triangulate.h"

namespace blvd::bake {
namespace {

Ring rect(double x0, double y0, double x1, double y1) {
  return Ring{{{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}};
}

Ring reversed(Ring r) {
  std::reverse(r.pts.begin(), r.pts.end());
  return r;
}

Ring circle(glm::dvec2 c, double r, int n) {
  constexpr double kPi = 3.14159265358979323846;
  Ring ring;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * kPi * i / n;
    ring.pts.push_back(c + r * glm::dvec2(std::cos(a), std::sin(a)));
  }
  return ring;
}

double triArea(const Triangulation& t, size_t tri) {
  const glm::dvec2 a = t.vertices[t.indices[3 * tri]];
  const glm::dvec2 b = t.vertices[t.indices[3 * tri + 1]] - a;
  const glm::dvec2 c = t.vertices[t.indices[3 * tri + 2]] - a;
  return 0.5 * (b.x * c.y - b.y * c.x);
}

// Invariants every successful result must satisfy.
void expectWellFormed(const Triangulation& t) {
  ASSERT_EQ(t.indices.size() % 3, 0u);
  ASSERT_EQ(t.boundary.size() % 2, 0u);
  for (uint32_t i : t.indices) ASSERT_LT(i, t.vertices.size());
  for (uint32_t i : t.boundary) ASSERT_LT(i, t.vertices.size());
  for (size_t k = 0; k < t.triangleCount(); ++k) EXPECT_GT(triArea(t, k), 0.0) << "triangle " << k;
  // Every outline edge is an edge of a kept triangle, in the same direction
  // (the kept region on its left).
  std::set<std::pair<uint32_t, uint32_t>> directed;
  for (size_t k = 0; k < t.triangleCount(); ++k) {
    for (int e = 0; e < 3; ++e) {
      directed.emplace(t.indices[3 * k + e], t.indices[3 * k + (e + 1) % 3]);
    }
  }
  for (size_t e = 0; e + 1 < t.boundary.size(); e += 2) {
    EXPECT_TRUE(directed.count({t.boundary[e], t.boundary[e + 1]})) << "outline edge " << e / 2;
    EXPECT_FALSE(directed.count({t.boundary[e + 1], t.boundary[e]})) << "outline edge " << e / 2;
  }
}

double outlineLength(const Triangulation& t) {
  double len = 0.0;
  for (size_t e = 0; e + 1 < t.boundary.size(); e += 2) {
    len += glm::length(t.vertices[t.boundary[e + 1]] - t.vertices[t.boundary[e]]);
  }
  return len;
}

Triangulation mustTriangulate(const Polygon2& p) {
  Triangulation t;
  std::string why;
  EXPECT_TRUE(triangulate(p, t, why)) << why;
  expectWellFormed(t);
  return t;
}

TEST(Triangulate, Square) {
  const Triangulation t = mustTriangulate({rect(0, 0, 1, 1), {}});
  EXPECT_EQ(t.triangleCount(), 2u);
  EXPECT_EQ(t.vertices.size(), 4u);
  EXPECT_NEAR(area(t), 1.0, 1e-12);
  EXPECT_EQ(t.boundary.size(), 8u);
  EXPECT_NEAR(outlineLength(t), 4.0, 1e-12);
}

TEST(Triangulate, ClockwiseInputGivesCounterClockwiseTriangles) {
  const Polygon2 p{reversed(rect(0, 0, 3, 2)), {}};
  EXPECT_LT(signedArea(p.outer), 0.0);
  const Triangulation t = mustTriangulate(p);  // checks every triangle's area > 0
  EXPECT_NEAR(area(t), 6.0, 1e-12);
}

TEST(Triangulate, SquareWithHole) {
  const Triangulation t = mustTriangulate({rect(0, 0, 10, 10), {rect(3, 3, 7, 7)}});
  EXPECT_NEAR(area(t), 100.0 - 16.0, 1e-9);
  EXPECT_NEAR(outlineLength(t), 40.0 + 16.0, 1e-9);
}

TEST(Triangulate, HoleWindingDoesNotMatter) {
  const Triangulation a = mustTriangulate({rect(0, 0, 10, 10), {rect(3, 3, 7, 7)}});
  const Triangulation b =
      mustTriangulate({reversed(rect(0, 0, 10, 10)), {reversed(rect(3, 3, 7, 7))}});
  EXPECT_NEAR(area(a), area(b), 1e-9);
}

TEST(Triangulate, CollinearPointsOnEdges) {
  Ring r{{{0, 0}, {0.5, 0}, {1, 0}, {1, 0.25}, {1, 0.5}, {1, 1}, {0.5, 1}, {0, 1}, {0, 0.5}}};
  const Triangulation t = mustTriangulate({r, {}});
  EXPECT_NEAR(area(t), 1.0, 1e-12);
  EXPECT_EQ(t.vertices.size(), 9u);
  EXPECT_NEAR(outlineLength(t), 4.0, 1e-12);
}

TEST(Triangulate, DuplicatePoints) {
  // Repeated nodes and the OSM closing node.
  Ring r{{{0, 0}, {0, 0}, {2, 0}, {2, 0}, {2, 0}, {2, 2}, {0, 2}, {0, 0}}};
  const Triangulation t = mustTriangulate({r, {}});
  EXPECT_NEAR(area(t), 4.0, 1e-12);
  EXPECT_EQ(t.vertices.size(), 4u);
}

TEST(Triangulate, SelfTouchingRing) {
  // A figure 8: two unit squares sharing the corner (1,1), walked as one ring.
  Ring r{{{0, 0}, {1, 0}, {1, 1}, {2, 1}, {2, 2}, {1, 2}, {1, 1}, {0, 1}}};
  const Triangulation t = mustTriangulate({r, {}});
  EXPECT_NEAR(area(t), 2.0, 1e-12);
  EXPECT_NEAR(outlineLength(t), 8.0, 1e-12);
}

TEST(Triangulate, HolesTouchingEachOther) {
  // Two holes sharing the edge x = 5: together they make one 6 x 6 hole.
  const Triangulation t =
      mustTriangulate({rect(0, 0, 10, 10), {rect(2, 2, 5, 8), rect(5, 2, 8, 8)}});
  EXPECT_NEAR(area(t), 100.0 - 36.0, 1e-9);
  // The shared edge is not part of the outline (no wall between courtyards).
  EXPECT_NEAR(outlineLength(t), 40.0 + 24.0, 1e-9);
}

TEST(Triangulate, HolesTouchingAtACorner) {
  const Triangulation t =
      mustTriangulate({rect(0, 0, 10, 10), {rect(2, 2, 5, 5), rect(5, 5, 8, 8)}});
  EXPECT_NEAR(area(t), 100.0 - 18.0, 1e-9);
}

TEST(Triangulate, HoleSharingAnEdgeWithTheOuterRing) {
  // A notch: the hole lies on the outer ring's left edge. Counting each
  // constrained edge as one crossing would fill it.
  const Triangulation t = mustTriangulate({rect(0, 0, 10, 10), {rect(0, 3, 4, 6)}});
  EXPECT_NEAR(area(t), 100.0 - 12.0, 1e-9);
}

TEST(Triangulate, OverlappingHolesFollowEvenOdd) {
  // Where the holes overlap, the outer ring and both holes are crossed.
  const Triangulation t =
      mustTriangulate({rect(0, 0, 10, 10), {rect(2, 2, 6, 6), rect(4, 4, 8, 8)}});
  EXPECT_NEAR(area(t), 100.0 - 16.0 - 16.0 + 2.0 * 4.0, 1e-9);
}

TEST(Triangulate, BowTie) {
  // Edges (0,0)-(2,2) and (2,0)-(0,2) cross at (1,1); both lobes are kept.
  Ring r{{{0, 0}, {2, 2}, {2, 0}, {0, 2}}};
  EXPECT_NEAR(signedArea(r), 0.0, 1e-12);  // why signed area cannot orient it
  const Triangulation t = mustTriangulate({r, {}});
  EXPECT_NEAR(area(t), 2.0, 1e-9);
  EXPECT_EQ(t.triangleCount(), 2u);
  EXPECT_EQ(t.vertices.size(), 5u);
}

TEST(Triangulate, SpikeIsIgnored) {
  // The ring runs out to (5,0.5) and straight back: that edge is walked twice.
  Ring r{{{0, 0}, {1, 0}, {1, 0.5}, {5, 0.5}, {1, 0.5}, {1, 1}, {0, 1}}};
  const Triangulation t = mustTriangulate({r, {}});
  EXPECT_NEAR(area(t), 1.0, 1e-12);
  EXPECT_NEAR(outlineLength(t), 4.0, 1e-12);
}

TEST(Triangulate, DegenerateHoleIsIgnored) {
  const Triangulation t =
      mustTriangulate({rect(0, 0, 4, 4), {Ring{{{1, 1}, {2, 2}}}, Ring{{{1, 1}, {2, 2}, {3, 3}}}}});
  EXPECT_NEAR(area(t), 16.0, 1e-12);
}

TEST(Triangulate, RejectsUnusablePolygons) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const std::pair<const char*, Polygon2> cases[] = {
      {"empty", {Ring{}, {}}},
      {"two points", {Ring{{{0, 0}, {1, 1}}}, {}}},
      {"two distinct points", {Ring{{{0, 0}, {1, 1}, {0, 0}, {1, 1}}}, {}}},
      {"collinear", {Ring{{{0, 0}, {1, 1}, {2, 2}, {5, 5}}}, {}}},
      {"NaN", {Ring{{{0, 0}, {1, 0}, {nan, 1}}}, {}}},
      {"infinity", {Ring{{{0, 0}, {inf, 0}, {1, 1}}}, {}}},
      {"NaN in hole", {rect(0, 0, 4, 4), {Ring{{{1, 1}, {2, 1}, {2, nan}}}}}},
      {"hole covers all", {rect(0, 0, 4, 4), {rect(0, 0, 4, 4)}}},
  };
  for (const auto& [name, poly] : cases) {
    Triangulation t;
    t.vertices.push_back({9, 9});  // must be cleared
    std::string why;
    EXPECT_FALSE(triangulate(poly, t, why)) << name;
    EXPECT_FALSE(why.empty()) << name;
    EXPECT_TRUE(t.vertices.empty() && t.indices.empty() && t.boundary.empty()) << name;
  }
}

TEST(Triangulate, CircleWithFiftyHoles) {
  Polygon2 p{circle({0, 0}, 100.0, 500), {}};
  double expected = signedArea(p.outer);
  for (int i = 0; i < 50; ++i) {
    const glm::dvec2 c(-60.0 + 15.0 * (i % 10), -30.0 + 15.0 * (i / 10));
    p.inners.push_back(circle(c, 5.0, 16));
    expected -= signedArea(p.inners.back());
  }
  const Triangulation t = mustTriangulate(p);
  EXPECT_NEAR(area(t), expected, 1e-6 * expected);
  EXPECT_EQ(t.vertices.size(), 500u + 50u * 16u);
  // A polygon with V vertices and H holes has exactly V + 2H - 2 triangles:
  // no Steiner points were added.
  EXPECT_EQ(t.indices.size() / 3, 500u + 50u * 16u + 2u * 50u - 2u);
}

TEST(Triangulate, RandomRingsNeverFail) {
  // Random (mostly self-intersecting) rings: never a crash, always CCW
  // triangles inside the bounding box, area no larger than the box.
  std::mt19937 rng(1234);
  std::uniform_real_distribution<double> coord(0.0, 10.0);
  std::uniform_int_distribution<int> count(3, 12);
  int succeeded = 0;
  for (int iter = 0; iter < 300; ++iter) {
    Polygon2 p;
    for (int k = count(rng); k > 0; --k) p.outer.pts.push_back({coord(rng), coord(rng)});
    if (iter % 3 == 0) {
      Ring hole;
      for (int k = count(rng); k > 0; --k) hole.pts.push_back({coord(rng), coord(rng)});
      p.inners.push_back(hole);
    }
    if (iter % 5 == 0) p.outer.pts.push_back(p.outer.pts[1]);  // revisit a node
    Triangulation t;
    std::string why;
    if (!triangulate(p, t, why)) {
      EXPECT_FALSE(why.empty());
      continue;
    }
    ++succeeded;
    expectWellFormed(t);
    EXPECT_LE(area(t), 100.0 + 1e-9);
    for (const glm::dvec2& v : t.vertices) {
      EXPECT_TRUE(v.x >= -1e-9 && v.x <= 10.0 + 1e-9 && v.y >= -1e-9 && v.y <= 10.0 + 1e-9);
    }
  }
  EXPECT_GT(succeeded, 250);  // random rings almost always enclose some area
}

TEST(Triangulate, FarFromOriginAndNearlyCollinear) {
  // Kilometres from the frame origin, with a vertex a micrometre off a line.
  const glm::dvec2 o(4000.0, -2500.0);
  Ring r{{o, o + glm::dvec2(10, 0), o + glm::dvec2(20, 1e-6), o + glm::dvec2(20, 5),
          o + glm::dvec2(0, 5)}};
  const Triangulation t = mustTriangulate({r, {}});
  EXPECT_NEAR(area(t), signedArea(r), 1e-6);
}

TEST(TriangulateSegments, BlockWithDeadEndStreet) {
  // A 10 x 10 block whose face boundary also walks a dead-end street into it
  // and back, plus a street crossing the outside corner.
  std::vector<Segment2> segs = {
      {{0, 0}, {10, 0}}, {{10, 0}, {10, 10}}, {{10, 10}, {0, 10}}, {{0, 10}, {0, 0}},
      {{0, 5}, {4, 5}},  {{4, 5}, {0, 5}},    {{8, 12}, {12, 8}},  {{3, 3}, {3, 3}},
  };
  auto inside = [](glm::dvec2 c) { return c.x > 0 && c.x < 10 && c.y > 0 && c.y < 10; };
  Triangulation t;
  std::string why;
  ASSERT_TRUE(triangulateSegments(segs, inside, t, why)) << why;
  expectWellFormed(t);
  EXPECT_NEAR(area(t), 100.0, 1e-9);
  EXPECT_NEAR(outlineLength(t), 40.0, 1e-9);  // the dead end has triangles on both sides
}

TEST(TriangulateSegments, RejectsBadInput) {
  auto all = [](glm::dvec2) { return true; };
  auto none = [](glm::dvec2) { return false; };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Triangulation t;
  std::string why;
  EXPECT_FALSE(triangulateSegments({{{0, 0}, {1, 1}}, {{1, 1}, {2, 2}}}, all, t, why));
  EXPECT_FALSE(why.empty());
  EXPECT_FALSE(triangulateSegments({{{0, 0}, {1, 0}}, {{1, 0}, {nan, 1}}}, all, t, why));
  EXPECT_FALSE(triangulateSegments({{{0, 0}, {1, 0}}, {{1, 0}, {0, 1}}}, none, t, why));
  EXPECT_FALSE(triangulateSegments({{{0, 0}, {1, 0}}, {{1, 0}, {0, 1}}}, nullptr, t, why));
  EXPECT_TRUE(t.indices.empty());
}

TEST(TriangulateSegments, ThrowingPredicateIsCaught) {
  auto bad = [](glm::dvec2) -> bool { throw std::runtime_error("boom"); };
  Triangulation t;
  std::string why;
  EXPECT_FALSE(triangulateSegments({{{0, 0}, {1, 0}}, {{1, 0}, {0, 1}}}, bad, t, why));
  EXPECT_NE(why.find("boom"), std::string::npos);
}

}  // namespace
}  // namespace blvd::bake
