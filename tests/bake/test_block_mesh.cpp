// Street ribbons (appendHalfStreet) where two streets overlap: the one of
// higher rank lies above the other (streetLift), so a driver sees one surface
// there, never rows of one grey through the other.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <vector>

#include <glm/vec2.hpp>

#include "bake/block_mesh.h"
#include "bake/capture.h"
#include "core/math.h"

namespace blvd::bake {
namespace {

// Two-way streets from (x, 0) to (x, 200) metres (east, north), each with
// its twin, `width` wide: half-edges 2i and 2i + 1 are street i.
graph::StreetGraph parallelStreets(const std::vector<double>& xs, const std::vector<graph::RoadClass>& classes,
                                   const std::vector<uint8_t>& flags, float width) {
  graph::StreetGraph g;
  for (size_t i = 0; i < xs.size(); ++i) {
    const auto p = static_cast<uint32_t>(g.points.size());
    g.points.insert(g.points.end(), {{xs[i], 0.0}, {xs[i], 200.0}, {xs[i], 0.0}});
    for (uint32_t k = 0; k < 2; ++k) {
      graph::HalfEdge e;
      e.twin = static_cast<uint32_t>(2 * i + 1 - k);
      e.pts_begin = p + k;  // the twin runs back: points p+1, p+2
      e.pts_count = 2;
      e.length = 200.0f;
      e.width = width;
      e.road_class = classes[i];
      e.flags = flags[i];
      g.halfedges.push_back(e);
    }
  }
  return g;
}

// Every vertex height (glTF y) of half-edge h's ribbon.
std::vector<float> ribbonHeights(const graph::StreetGraph& g, uint32_t h) {
  geo::MeshData m;
  appendHalfStreet(g, h, m);
  std::vector<float> y;
  for (size_t v = 0; v < m.vertexCount(); ++v) y.push_back(m.positions[3 * v + 1]);
  return y;
}

TEST(StreetRibbons, RankedByClassThenBridge) {
  using graph::RoadClass;
  const graph::StreetGraph g =
      parallelStreets({0, 20, 40, 60}, {RoadClass::Residential, RoadClass::Secondary, RoadClass::Service, RoadClass::Primary},
                      {0, 0, graph::kBridge, graph::kBridge}, 8.0f);
  const double want[4] = {kStreetLift, kStreetLift + kStreetRankLift, kStreetLift + 2 * kStreetRankLift,
                          kStreetLift + 3 * kStreetRankLift};
  for (uint32_t s = 0; s < 4; ++s)
    for (uint32_t h : {2 * s, 2 * s + 1}) {
      const std::vector<float> y = ribbonHeights(g, h);
      ASSERT_EQ(y.size(), 4u);
      for (float v : y) EXPECT_FLOAT_EQ(v, float(want[s])) << "street " << s << " half-edge " << h;
    }
}

// A residential street and a secondary one 3 m apart, 8 m wide: their
// ribbons overlap over 5 m. Seen from a driver's eye down the overlap, every
// pixel the secondary's ribbon covers when drawn alone shows it when both
// are drawn as one block (the bake's blocks hold both halves of every street
// around them).
TEST(StreetRibbons, TheMajorRoadCoversTheMinorOneWhereTheyOverlap) {
  const graph::StreetGraph g =
      parallelStreets({0, 3}, {graph::RoadClass::Residential, graph::RoadClass::Secondary}, {0, 0}, 8.0f);
  geo::MeshData both, major;
  for (uint32_t h = 0; h < 4; ++h) appendHalfStreet(g, h, both);
  for (uint32_t h = 2; h < 4; ++h) appendHalfStreet(g, h, major);
  constexpr int kRes = 256;
  CaptureRig rig({both, major}, kRes, kRes);
  render::Camera cam;
  cam.eye_enu = {1.5, 2.0, 1.2};
  cam.pitch_deg = -20.0;
  cam.fov_y_deg = 60.0;
  cam.width = cam.height = kRes;
  CaptureImage a, b;
  PinholeCamera pin;
  rig.capture(cam, {0}, a, pin);
  rig.capture(cam, {1}, b, pin);
  size_t covered = 0, wrong = 0;
  for (size_t i = 0; i < size_t(kRes) * kRes; ++i) {
    if (!(b.depth[i] > 0 && b.depth[i] < 1e15f)) continue;
    ++covered;
    int diff = 0;
    for (int c = 0; c < 3; ++c) diff += std::abs(int(a.rgba[4 * i + c]) - int(b.rgba[4 * i + c]));
    wrong += diff > 3;
  }
  EXPECT_GT(covered, size_t(kRes) * kRes / 8) << "the secondary's ribbon should fill much of the view";
  EXPECT_EQ(wrong, 0u) << "of " << covered << " pixels of the secondary's ribbon, these show the residential street";
}

// Whether ground point (east, north) lies under a triangle of `m` (glTF:
// x east, z south).
bool covers(const geo::MeshData& m, double east, double north) {
  auto at = [&](uint32_t i) { return glm::dvec2(m.positions[3 * i], -m.positions[3 * i + 2]); };
  const glm::dvec2 q(east, north);
  for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
    const glm::dvec2 a = at(m.indices[t]), b = at(m.indices[t + 1]), c = at(m.indices[t + 2]);
    auto side = [&](glm::dvec2 u, glm::dvec2 v) { return (v.x - u.x) * (q.y - u.y) - (v.y - u.y) * (q.x - u.x); };
    const double s0 = side(a, b), s1 = side(b, c), s2 = side(c, a);
    if ((s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0)) return true;
  }
  return false;
}

// Two streets meeting at a node with a 10° turn, each ribbon ending square
// to its own last segment: without the ends reaching past the node, a wedge
// on the outer side of the turn is left open and what lies beneath (a minor
// street, the ground) shows through it as a line across the road.
TEST(StreetRibbons, TwoStreetsMeetingAtAnAngleLeaveNoSeam) {
  graph::StreetGraph g;
  const double turn = 10.0 * core::kDegToRad;
  g.points = {{0.0, -50.0}, {0.0, 0.0}, {0.0, 0.0}, {50.0 * std::sin(turn), 50.0 * std::cos(turn)}};
  for (uint32_t k = 0; k < 2; ++k) {
    graph::HalfEdge e;
    e.pts_begin = 2 * k;
    e.pts_count = 2;
    e.length = 50.0f;
    e.width = 8.0f;
    e.road_class = graph::RoadClass::Primary;
    g.halfedges.push_back(e);
  }
  geo::MeshData both;
  appendHalfStreet(g, 0, both);
  appendHalfStreet(g, 1, both);
  // The ribbons lie on the left of the streets, which turn right: the
  // wedge between the two square ends opens on the left, between the
  // directions west (-cos a, sin a) for a from 0 to the turn.
  size_t open = 0, tried = 0;
  for (double r = 0.2; r <= 3.9; r += 0.1)
    for (int k = 0; k <= 16; ++k) {
      const double a = turn * k / 16;
      ++tried;
      open += !covers(both, -r * std::cos(a), r * std::sin(a));
    }
  EXPECT_EQ(open, 0u) << "of " << tried << " points around the junction's outer corner";
}

}  // namespace
}  // namespace blvd::bake
