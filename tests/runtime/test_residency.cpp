// Residency order and eviction on a hand-made junction ("unit tests
// of residency and eviction order").
#include <gtest/gtest.h>

#include <vector>

#include "stream/residency.h"

namespace blvd::stream {
namespace {

using graph::kNone;

// Cell 0 runs north from (0,0) to (0,100). At its end: 1 straight on to
// (0,200), 2 right to (100,100), 3 left to (-100,100). After 1: 4 to (0,300);
// after 2: 5 to (200,100).
graph::StreetGraph junction() {
  graph::StreetGraph g;
  const glm::dvec2 seg[6][2] = {{{0, 0}, {0, 100}},     {{0, 100}, {0, 200}},   {{0, 100}, {100, 100}},
                                {{0, 100}, {-100, 100}}, {{0, 200}, {0, 300}}, {{100, 100}, {200, 100}}};
  for (int c = 0; c < 6; ++c) {
    graph::HalfEdge e;
    e.pts_begin = static_cast<uint32_t>(g.points.size());
    e.pts_count = 2;
    e.length = 100;
    g.points.push_back(seg[c][0]);
    g.points.push_back(seg[c][1]);
    g.halfedges.push_back(e);
  }
  g.successors = graph::Csr{};
  g.successors.push({1, 2, 3});
  g.successors.push({4});
  g.successors.push({5});
  g.successors.push({});
  g.successors.push({});
  g.successors.push({});
  return g;
}

std::vector<uint32_t> wanted(const Residency& r) { return {r.wanted(), r.wanted() + r.wantedCount()}; }

TEST(Residency, CurrentFirstThenStraightOnBeforeTurns) {
  const graph::StreetGraph g = junction();
  Residency r(g, 4, 16);
  r.update({0, 0.0, 0.0});
  // Standing: 1 costs 100 m, a 90° turn 100 + 20 m, 4 costs 200 m.
  EXPECT_EQ(wanted(r), (std::vector<uint32_t>{0, 1, 2, 3}));
  EXPECT_EQ(r.rank(0), 0u);
  EXPECT_EQ(r.rank(3), 3u);
  EXPECT_EQ(r.rank(5), kNone);
}

TEST(Residency, SpeedMakesTurnsLessLikely) {
  const graph::StreetGraph g = junction();
  Residency r(g, 4, 16);
  // At 50 m/s a 90° turn costs 20 + 100 m: the cell after the straight one
  // (200 m) now comes before either turn (220 m).
  r.update({0, 0.0, 50.0});
  EXPECT_EQ(wanted(r), (std::vector<uint32_t>{0, 1, 4, 2}));
  EXPECT_DOUBLE_EQ(Residency::turnPenalty(90, 50), 120.0);
  EXPECT_DOUBLE_EQ(Residency::turnPenalty(0, 50), 0.0);
}

TEST(Residency, PositionAlongTheCellCountsOnlyWhatIsLeft) {
  const graph::StreetGraph g = junction();
  Residency r(g, 2, 16);
  r.update({0, 90.0, 0.0});
  EXPECT_EQ(wanted(r), (std::vector<uint32_t>{0, 1}));
}

TEST(Residency, RouteReplacesTheGuess) {
  const graph::StreetGraph g = junction();
  Residency r(g, 4, 3);
  const uint32_t route[] = {0, 2, 5};
  ASSERT_TRUE(r.setRoute(route, 3));
  r.update({0, 0.0, 0.0});
  EXPECT_EQ(wanted(r), (std::vector<uint32_t>{0, 2, 5}));
  // Off the route: back to guessing from the current cell.
  r.update({1, 0.0, 0.0});
  EXPECT_EQ(wanted(r), (std::vector<uint32_t>{1, 4}));
  // Too long or out of range: refused, and the route is cleared.
  const uint32_t longer[] = {0, 1, 4, 4};
  EXPECT_FALSE(r.setRoute(longer, 4));
  const uint32_t bad[] = {0, 99};
  EXPECT_FALSE(r.setRoute(bad, 2));
  r.update({0, 0.0, 0.0});
  EXPECT_EQ(wanted(r), (std::vector<uint32_t>{0, 1, 2, 3}));
}

TEST(Residency, ALoopingRouteIsFollowedVisitByVisit) {
  const graph::StreetGraph g = junction();
  Residency r(g, 3, 8);
  // 0 is passed twice: first on to 2, then on to 1 (the cells need not
  // connect for the route's order to hold).
  const uint32_t route[] = {0, 2, 5, 0, 1, 4};
  ASSERT_TRUE(r.setRoute(route, 6));
  r.update({0, 0.0, 0.0});
  EXPECT_EQ(wanted(r), (std::vector<uint32_t>{0, 2, 5}));
  EXPECT_EQ(r.nextOnRoute(0), 2u);
  r.update({2, 0.0, 0.0});
  r.update({5, 0.0, 0.0});
  r.update({0, 0.0, 0.0});  // the second visit
  EXPECT_EQ(wanted(r), (std::vector<uint32_t>{0, 1, 4}));
  EXPECT_EQ(r.nextOnRoute(0), 1u);
  // Back to the route's start (a host that drives it again): its first visit.
  r.update({2, 0.0, 0.0});
  EXPECT_EQ(wanted(r), (std::vector<uint32_t>{2, 5, 0}));
  EXPECT_EQ(r.nextOnRoute(5), 0u);
}

TEST(Residency, EvictsEmptyThenFurthestUnwantedThenLeastWanted) {
  const graph::StreetGraph g = junction();
  Residency r(g, 4, 16);
  r.update({0, 0.0, 0.0});  // wanted 0, 1, 2, 3
  {
    const uint32_t resident[] = {5, kNone, 1, 0};
    EXPECT_EQ(r.victim(resident, 4, 2), 1u);  // the empty slot
  }
  {
    // 4 starts 200 m from cell 0's start, 5 starts 141 m away: 4 goes first.
    const uint32_t resident[] = {5, 4, 1, 0};
    EXPECT_EQ(r.victim(resident, 4, 2), 1u);
    const uint32_t one_unwanted[] = {5, 2, 1, 0};
    EXPECT_EQ(r.victim(one_unwanted, 4, 3), 0u);
  }
  {
    // All wanted: the least wanted goes, but only for a more wanted cell.
    const uint32_t resident[] = {3, 2, 1, 0};
    EXPECT_EQ(r.victim(resident, 4, 1), 0u);  // cell 3 (rank 3) for a rank-1 cell
    EXPECT_EQ(r.victim(resident, 4, 3), kNone);
  }
}

TEST(Residency, AKeptSlotNeverGoes) {
  const graph::StreetGraph g = junction();
  Residency r(g, 4, 16);
  r.update({0, 0.0, 0.0});  // wanted 0, 1, 2, 3
  {
    // Unwanted 4 and 5 (4 the further): with 4 kept, 5 goes.
    const uint32_t resident[] = {5, 4, 1, 0};
    const bool kept[] = {false, true, false, false};
    EXPECT_EQ(r.victim(resident, 4, 2, kept), 0u);
    const bool both[] = {true, true, false, false};
    EXPECT_EQ(r.victim(resident, 4, 2, both), kNone);  // 1 and 0 rank above 2
  }
  {
    // All wanted: the least wanted (3) is kept, so the next (2) goes for a rank-1 cell.
    const uint32_t resident[] = {3, 2, 1, 0};
    const bool kept[] = {true, false, false, false};
    EXPECT_EQ(r.victim(resident, 4, 1, kept), 1u);
  }
}

TEST(Residency, NoCellWantsNothing) {
  const graph::StreetGraph g = junction();
  Residency r(g, 4, 16);
  r.update({kNone, 0.0, 0.0});
  EXPECT_EQ(r.wantedCount(), 0u);
}

}  // namespace
}  // namespace blvd::stream
