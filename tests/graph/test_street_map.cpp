// Street map construction on small hand-made networks where the answer is known.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "bake/local_model.h"
#include "bake/street_map.h"
#include "graph_test_util.h"

using namespace blvd;
using blvd::test::street;

namespace {
std::vector<uint32_t> successors(const graph::StreetGraph& g, uint32_t h) {
  return {g.successors.begin(h), g.successors.end(h)};
}
uint32_t findCell(const graph::StreetGraph& g, glm::dvec2 from, glm::dvec2 to) {
  for (uint32_t h = 0; h < g.halfedges.size(); ++h) {
    const auto& e = g.halfedges[h];
    if (g.points[e.pts_begin] == from && g.points[e.pts_begin + e.pts_count - 1] == to) return h;
  }
  return graph::kNone;
}
std::vector<uint32_t> localBlocks(const graph::StreetGraph& g, uint32_t cell) {
  return {g.local_blocks.begin(cell), g.local_blocks.end(cell)};
}
bool has(const std::vector<uint32_t>& v, uint32_t f) { return std::find(v.begin(), v.end(), f) != v.end(); }
// A main road y = 0 with junctions at x = 0, 50, 100, 150, 250, 300; a
// service road beside it (up at x = 50, along y = 8, down at x = 250);
// streets south from x = 100 and 150; a ring closing the block north.
std::vector<bake::OsmStreet> mainRoadWithServiceRoad() {
  std::vector<bake::OsmStreet> s;
  s.push_back(street(1, {1, 2, 3, 4, 5, 6}, {{0, 0}, {50, 0}, {100, 0}, {150, 0}, {250, 0}, {300, 0}}));
  s.push_back(street(2, {2, 10, 11, 5}, {{50, 0}, {50, 8}, {250, 8}, {250, 0}}));
  s.push_back(street(3, {3, 20}, {{100, 0}, {100, -60}}));
  s.push_back(street(4, {4, 21}, {{150, 0}, {150, -60}}));
  s.push_back(street(5, {1, 30, 31, 6}, {{0, 0}, {0, 60}, {300, 60}, {300, 0}}));
  return s;
}
}  // namespace

TEST(StreetMap, GridOfFourBlocks) {
  // A 3x3 lattice of streets sharing nodes. The four corners have degree 2, so
  // they are bends inside polylines: 5 junctions (4 T's + the centre), 8 edges,
  // 4 blocks + outside.
  std::vector<bake::OsmStreet> s;
  for (int i = 0; i < 3; ++i) {
    s.push_back(street(10 + i, {100 + i * 3, 101 + i * 3, 102 + i * 3}, {{0, i * 100.0}, {100, i * 100.0}, {200, i * 100.0}}));
    s.push_back(street(20 + i, {100 + i, 103 + i, 106 + i}, {{i * 100.0, 0}, {i * 100.0, 100}, {i * 100.0, 200}}));
  }
  bake::StreetMap map(s);
  const graph::StreetGraph& g = map.graph();
  EXPECT_EQ(g.vertices.size(), 5u);
  EXPECT_EQ(g.halfedges.size(), 16u);
  EXPECT_EQ(g.faces.size(), 5u);
  EXPECT_EQ(g.junctionCount(), 5u);
  const auto bad = graph::checkInvariants(g);
  EXPECT_TRUE(bad.empty()) << bad.front();
  // Each block has area 100x100.
  int bounded = 0;
  for (const auto& f : g.faces)
    if (!f.unbounded) {
      ++bounded;
      EXPECT_NEAR(f.area, 1e4, 1e-6);
    }
  EXPECT_EQ(bounded, 4);
  // From the centre junction eastwards, a vehicle can turn left, go straight or turn right.
  const uint32_t h = findCell(g, {0, 100}, {100, 100});
  ASSERT_NE(h, graph::kNone);
  EXPECT_EQ(successors(g, h).size(), 3u);
  // Local blocks of a centre street: the two sides plus those at both end junctions = all 4 + outside.
  EXPECT_EQ(g.local_blocks.count(h), 5u);
  // Points inside each quadrant land in distinct faces.
  const uint32_t f1 = map.locateFace({50, 50}), f2 = map.locateFace({150, 50}), f3 = map.locateFace({50, 150});
  EXPECT_NE(f1, f2);
  EXPECT_NE(f1, f3);
  EXPECT_TRUE(g.faces[map.locateFace({500, 500})].unbounded);
}

TEST(StreetMap, BridgeCrossingIsNotAJunction) {
  // Street A (west-east) crosses bridge B (south-north) without a shared node.
  std::vector<bake::OsmStreet> s = {
      street(1, {1, 2}, {{-100, 0}, {100, 0}}),
      street(2, {3, 4}, {{0, -100}, {0, 100}}, 1),
  };
  bake::StreetMap map(s);
  const graph::StreetGraph& g = map.graph();
  EXPECT_TRUE(graph::checkInvariants(g).empty());
  ASSERT_EQ(g.vertices.size(), 5u);  // four ends + the crossing
  size_t crossings = 0;
  for (const auto& v : g.vertices) crossings += v.kind == graph::VertexKind::Crossing;
  EXPECT_EQ(crossings, 1u);
  EXPECT_EQ(g.junctionCount(), 4u);  // the dead ends only
  // A vehicle on A reaching the crossing can only continue on A.
  const uint32_t h = findCell(g, {-100, 0}, {0, 0});
  ASSERT_NE(h, graph::kNone);
  const auto succ = successors(g, h);
  ASSERT_EQ(succ.size(), 1u);
  EXPECT_EQ(g.halfedges[succ[0]].osm_way, 1);
  EXPECT_EQ(g.points[g.halfedges[succ[0]].pts_begin + 1], glm::dvec2(100, 0));
}

TEST(StreetMap, SharedNodeMakesAJunction) {
  std::vector<bake::OsmStreet> s = {
      street(1, {1, 9, 2}, {{-100, 0}, {0, 0}, {100, 0}}),
      street(2, {3, 9, 4}, {{0, -100}, {0, 0}, {0, 100}}),
  };
  bake::StreetMap map(s);
  const graph::StreetGraph& g = map.graph();
  EXPECT_TRUE(graph::checkInvariants(g).empty());
  const uint32_t h = findCell(g, {-100, 0}, {0, 0});
  ASSERT_NE(h, graph::kNone);
  EXPECT_EQ(successors(g, h).size(), 3u);
  EXPECT_EQ(g.junctionCount(), 5u);
}

TEST(StreetMap, DegreeTwoVerticesBecomePolylines) {
  // One way with a bend, split into two OSM ways at a shared node: one edge, one polyline.
  std::vector<bake::OsmStreet> s = {
      street(1, {1, 2, 3}, {{0, 0}, {50, 10}, {100, 0}}),
      street(2, {3, 4}, {{100, 0}, {150, 40}}),
  };
  bake::StreetMap map(s);
  const graph::StreetGraph& g = map.graph();
  EXPECT_TRUE(graph::checkInvariants(g).empty());
  EXPECT_EQ(g.vertices.size(), 2u);
  ASSERT_EQ(g.halfedges.size(), 2u);
  EXPECT_EQ(g.halfedges[0].pts_count, 4u);
  EXPECT_NEAR(g.halfedges[0].length, std::hypot(50, 10) * 2 + std::hypot(50, 40), 1e-3);
  // Dead end both ways: the only successor is the U-turn.
  EXPECT_EQ(successors(g, 0), std::vector<uint32_t>{1});
}

TEST(StreetMap, IsolatedRingRoad) {
  std::vector<bake::OsmStreet> s = {street(1, {1, 2, 3, 4, 1}, {{0, 0}, {10, 0}, {10, 10}, {0, 10}, {0, 0}})};
  bake::StreetMap map(s);
  const graph::StreetGraph& g = map.graph();
  const auto bad = graph::checkInvariants(g);
  EXPECT_TRUE(bad.empty()) << bad.front();
  EXPECT_EQ(g.faces.size(), 2u);
}

TEST(StreetMap, TwoComponentsEuler) {
  std::vector<bake::OsmStreet> s = {
      street(1, {1, 2, 3, 4, 1}, {{0, 0}, {10, 0}, {10, 10}, {0, 10}, {0, 0}}),
      street(2, {5, 6}, {{100, 0}, {200, 0}}),
      street(3, {7, 8}, {{2, 2}, {8, 8}}),  // inside the ring: a hole in its face
  };
  bake::StreetMap map(s);
  const graph::StreetGraph& g = map.graph();
  EXPECT_EQ(g.componentCount(), 3u);
  const auto bad = graph::checkInvariants(g);
  EXPECT_TRUE(bad.empty()) << bad.front();
}

// A service road beside the main road leaves a thin face (a strip 8 m wide)
// between the two; the block beyond it touches neither the main road's cell
// nor its junctions, yet its building stands 12 m from that street.
// Topologically it is not local; within the local radius it is.
TEST(StreetMap, ABuildingNearTheStreetBeyondAThinFaceIsLocal) {
  bake::StreetMap map(mainRoadWithServiceRoad());
  graph::StreetGraph& g = map.graph();
  const uint32_t h = findCell(g, {100, 0}, {150, 0});
  ASSERT_NE(h, graph::kNone);
  bake::OsmBuilding b;
  b.polygons.push_back({{{{110, 12}, {140, 12}, {140, 30}, {110, 30}}}, {}});
  b.height = 20;
  const std::vector<bake::OsmBuilding> buildings = {b};
  const uint32_t beyond = map.locateFace({125, 20});
  std::vector<std::vector<uint32_t>> face_buildings(g.faces.size());
  face_buildings[beyond].push_back(0);
  auto local = [&](uint32_t cell) { return localBlocks(g, cell); };
  const std::vector<uint32_t> before = local(h);
  EXPECT_FALSE(has(before, beyond));
  bake::widenLocalModels(g, buildings, face_buildings, 10.0);  // 12 m away: not yet
  EXPECT_EQ(local(h), before);
  bake::widenLocalModels(g, buildings, face_buildings, 20.0);
  const std::vector<uint32_t> after = local(h);
  EXPECT_TRUE(has(after, beyond));
  EXPECT_EQ(after.size(), before.size() + 1);
  EXPECT_TRUE(std::equal(before.begin(), before.end(), after.begin()));  // the topological ones first
  EXPECT_TRUE(has(local(g.halfedges[h].twin), beyond));                   // both directions
  const auto bad = graph::checkInvariants(g);
  EXPECT_TRUE(bad.empty()) << bad.front();
}

// Two service roads beside the main road (y = 8 and 16): a strip of ground (no building)
// between them, 8 m from the main road, touching neither its cell nor its
// junctions. Within the local radius its ground is local; the block beyond
// it is not, since its only building stands 40 m from the street.
TEST(StreetMap, GroundWithoutABuildingNearTheStreetIsLocal) {
  std::vector<bake::OsmStreet> s = mainRoadWithServiceRoad();
  s.push_back(street(6, {10, 12, 13, 11}, {{50, 8}, {50, 16}, {250, 16}, {250, 8}}));  // a second one, y = 16
  bake::StreetMap map(s);
  graph::StreetGraph& g = map.graph();
  const uint32_t h = findCell(g, {100, 0}, {150, 0});
  ASSERT_NE(h, graph::kNone);
  const uint32_t strip = map.locateFace({125, 12}), beyond = map.locateFace({125, 40});
  bake::OsmBuilding b;
  b.polygons.push_back({{{{110, 40}, {140, 40}, {140, 55}, {110, 55}}}, {}});
  const std::vector<bake::OsmBuilding> buildings = {b};
  std::vector<std::vector<uint32_t>> face_buildings(g.faces.size());
  face_buildings[beyond].push_back(0);
  auto local = [&](uint32_t cell) { return localBlocks(g, cell); };
  const std::vector<uint32_t> before = local(h);
  EXPECT_FALSE(has(before, strip));
  bake::widenLocalModels(g, buildings, face_buildings, 5.0);  // 8 m away: not yet
  EXPECT_EQ(local(h), before);
  bake::widenLocalModels(g, buildings, face_buildings, 20.0);
  const std::vector<uint32_t> after = local(h);
  EXPECT_TRUE(has(after, strip));
  EXPECT_FALSE(has(after, beyond));  // its ground is 16 m away, its building 40 m
  EXPECT_TRUE(std::equal(before.begin(), before.end(), after.begin()));
  EXPECT_TRUE(has(local(g.halfedges[h].twin), strip));
}

TEST(StreetMap, ABlockAcrossAJunctionDrawnAsTwoVerticesIsLocal) {
  std::vector<bake::OsmStreet> s;
  // The main road y = 0 meets a street south at x = 100 and the crossing
  // street x = 106 six metres on: one junction drawn as two vertices.
  s.push_back(street(1, {1, 2, 3, 4}, {{0, 0}, {100, 0}, {106, 0}, {200, 0}}));
  s.push_back(street(2, {2, 20}, {{100, 0}, {100, -60}}));
  s.push_back(street(3, {21, 3, 22}, {{106, -60}, {106, 0}, {106, 60}}));
  s.push_back(street(4, {1, 30, 31, 4}, {{0, 0}, {0, 60}, {200, 60}, {200, 0}}));
  s.push_back(street(5, {1, 40, 20, 21, 41, 4}, {{0, 0}, {0, -60}, {100, -60}, {106, -60}, {200, -60}, {200, 0}}));
  bake::StreetMap map(s);
  graph::StreetGraph& g = map.graph();
  const uint32_t h = findCell(g, {0, 0}, {100, 0});
  ASSERT_NE(h, graph::kNone);
  const uint32_t ne = map.locateFace({150, 30}), se = map.locateFace({150, -30});
  auto local = [&](uint32_t cell) { return localBlocks(g, cell); };
  const std::vector<uint32_t> before = local(h);
  EXPECT_FALSE(has(before, ne));  // beyond the crossing street: no shared vertex
  EXPECT_FALSE(has(before, se));
  const std::vector<bake::OsmBuilding> none;
  const std::vector<std::vector<uint32_t>> no_buildings(g.faces.size());
  bake::widenLocalModels(g, none, no_buildings, 0.0, 5.0);  // the crossing is 6 m from the cell's end
  EXPECT_EQ(local(h), before);
  bake::widenLocalModels(g, none, no_buildings, 0.0, 8.0);
  const std::vector<uint32_t> after = local(h);
  EXPECT_TRUE(has(after, ne));
  EXPECT_TRUE(has(after, se));
  EXPECT_TRUE(std::equal(before.begin(), before.end(), after.begin()));  // the topological ones first
  EXPECT_TRUE(has(local(g.halfedges[h].twin), ne));                      // both directions
  const auto bad = graph::checkInvariants(g);
  EXPECT_TRUE(bad.empty()) << bad.front();
}
