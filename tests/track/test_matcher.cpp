// The HMM map matcher on hand-built graphs: the fixed-lag decision at a
// T-junction, direction (twin half-edges) from heading, the candidate bound, a
// chain break, following the graph between steps (turns, forks), the spatial
// index, and no allocation per step.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include "fault/alloc_counter.h"
#include "track/map_matcher.h"
#include "graph/segment_grid.h"
#include "track_test_util.h"

namespace blvd::track {
namespace {

using blvd_test::AllocCounter;

constexpr double kPi = 3.14159265358979323846;

MatchObservation obsAt(double t, double e, double n, double sigma = 4, double heading_deg = NAN) {
  MatchObservation o;
  o.t = t;
  o.e = e;
  o.n = n;
  o.sigma_m = sigma;
  if (std::isfinite(heading_deg)) {
    o.heading_rad = heading_deg * kPi / 180;
    o.heading_sigma_rad = 5 * kPi / 180;
  }
  return o;
}

// Observations of a drive up the stem that turns east; the one just past the
// junction leans west.
std::vector<MatchObservation> tJunctionDrive() {
  std::vector<MatchObservation> v;
  double time = 0;
  for (double n = -60; n <= -5; n += 10) v.push_back(obsAt(time++, 0.5, n));
  v.push_back(obsAt(time++, -8, 16));  // nearest the west branch
  for (double e = 20; e <= 80; e += 15) v.push_back(obsAt(time++, e, 21));
  return v;
}

TEST(MapMatcher, TJunctionSettlesOnTheBranchTakenAfterTheLag) {
  const auto t = blvd_test::makeTJunction();
  MatcherDesc desc;
  desc.lag = 3;
  MapMatcher m(t.g, desc);
  const auto drive = tJunctionDrive();
  const double ambiguous_t = 6;
  bool checked = false;
  for (const auto& o : drive) {
    ASSERT_TRUE(m.step(o));
    if (o.t < ambiguous_t) {
      EXPECT_EQ(m.head().cell, t.stem) << "t = " << o.t;
    } else if (o.t == ambiguous_t) {
      // The online answer follows the evidence so far: the west branch ...
      EXPECT_EQ(m.head().cell, t.west);
      bool saw_east = false;
      for (uint32_t i = 0; i < m.candidateCount(); ++i) saw_east |= m.candidate(i).cell == t.east;
      EXPECT_TRUE(saw_east) << "the east branch must be a candidate of the ambiguous step";
    } else {
      // ... then the vehicle is clearly going east; nothing connects the
      // branches within reach, so only a path through the east branch explains it.
      EXPECT_EQ(m.head().cell, t.east) << "t = " << o.t;
    }
    if (m.settled().cell != graph::kNone && m.settledTime() == ambiguous_t) {
      // The fixed-lag decision for the ambiguous step: the branch actually taken.
      EXPECT_EQ(m.settled().cell, t.east);
      EXPECT_EQ(o.t, ambiguous_t + desc.lag);
      checked = true;
    }
  }
  EXPECT_TRUE(checked) << "no settled decision for t = " << ambiguous_t;
  EXPECT_GT(m.confidence(), 0.9);
}

TEST(MapMatcher, HeadingPicksTheDirection) {
  const auto t = blvd_test::makeTJunction();
  MapMatcher m(t.g);
  // On the stem's centre line, heading north: the stem's north-bound half-edge.
  ASSERT_TRUE(m.step(obsAt(0, 0, -100, 3, 0)));
  EXPECT_EQ(m.head().cell, t.stem);
  EXPECT_NEAR(m.head().arc_m, 100, 1e-6);
  m.reset();
  // Heading south: its twin, with the arc measured from the other end.
  ASSERT_TRUE(m.step(obsAt(0, 0, -100, 3, 180)));
  EXPECT_EQ(m.head().cell, t.g.halfedges[t.stem].twin);
  EXPECT_NEAR(m.head().arc_m, 100, 1e-6);
  // Lateral offset is positive to the right of the half-edge's direction.
  m.reset();
  ASSERT_TRUE(m.step(obsAt(0, 2, -100, 3, 0)));
  EXPECT_NEAR(m.head().lateral_m, 2, 1e-9);
  EXPECT_NEAR(m.head().heading_rad, 0, 1e-9);
}

TEST(MapMatcher, BoundsTheCandidates) {
  // 30 parallel streets 4 m apart: far more half-edges in reach than K.
  blvd_test::GraphBuilder b;
  for (int i = 0; i < 30; ++i) b.street(b.vertex(i * 4.0, 0), b.vertex(i * 4.0, 300));
  const auto g = b.finish();
  MatcherDesc desc;
  desc.max_candidates = 6;
  MapMatcher m(g, desc);
  ASSERT_TRUE(m.step(obsAt(0, 60, 150, 10)));
  EXPECT_EQ(m.candidateCount(), 6u);
  std::set<uint32_t> cells;
  for (uint32_t i = 0; i < m.candidateCount(); ++i) cells.insert(m.candidate(i).cell);
  EXPECT_EQ(cells.size(), 6u);
  // The nearest street (x = 60) is among them.
  EXPECT_TRUE(cells.count(2 * 15) || cells.count(2 * 15 + 1));
}

TEST(MapMatcher, NoCandidateResetsAndAJumpBreaksTheChain) {
  // Two streets that do not connect.
  blvd_test::GraphBuilder b;
  const uint32_t a = b.street(b.vertex(0, 0), b.vertex(0, 300));
  const uint32_t c = b.street(b.vertex(60, 0), b.vertex(60, 300));
  const auto g = b.finish();
  MapMatcher m(g);
  ASSERT_TRUE(m.step(obsAt(0, 0, 100, 4, 0)));
  EXPECT_EQ(m.head().cell, a);
  EXPECT_FALSE(m.step(obsAt(1, 1000, 1000)));  // nowhere near a street
  EXPECT_EQ(m.head().cell, graph::kNone);
  EXPECT_EQ(m.stats().empty_steps, 1u);
  ASSERT_TRUE(m.step(obsAt(2, 0, 110, 4, 0)));
  EXPECT_EQ(m.stats().breaks, 0u);
  // A jump onto the other street: no route, the chain restarts there.
  ASSERT_TRUE(m.step(obsAt(3, 60, 120, 4, 0)));
  EXPECT_EQ(m.stats().breaks, 1u);
  EXPECT_EQ(m.head().cell, c);
}

TEST(MapMatcher, FollowMovesOntoTheSuccessor) {
  const auto t = blvd_test::makeTJunction();
  MapMatcher m(t.g);
  const CellPoint p = m.project(t.stem, 0, -3);
  ASSERT_EQ(p.cell, t.stem);
  // Past the stem's end, heading north-east: onto the east branch.
  const CellPoint q = m.follow(p, 3, 4, kPi / 4, 0.1);
  EXPECT_EQ(q.cell, t.east);
  EXPECT_NEAR(q.arc_m, 7 / std::sqrt(2.0), 1e-9);
  // Still on the stem: stays.
  EXPECT_EQ(m.follow(p, 0, -1, 0, 0.1).cell, t.stem);
}

// Turns at a junction, the vehicle 1.8 m right of the centre line: the street it
// is on is the one nearer to it (the corner's bisector), on the inside of a turn
// (where its projection on the first street never reaches the end) as on the
// outside (where every point beyond the end is nearest the junction itself).
TEST(MapMatcher, FollowTakesTheNearerStreetAtATurn) {
  blvd_test::GraphBuilder b;
  const uint32_t a = b.vertex(0, -100), j = b.vertex(0, 0), east = b.vertex(100, 0), west = b.vertex(-100, 0);
  const uint32_t north = b.street(a, j), to_east = b.street(j, east), to_west = b.street(j, west);
  const auto g = b.finish();
  MapMatcher m(g);
  const CellPoint p = m.project(north, 1.8, -10);
  ASSERT_EQ(p.cell, north);
  const double h = kPi / 4;  // half-way through a right turn (north-east)
  // Right turn, inside of the corner: before the bisector, still the first street ...
  EXPECT_EQ(m.follow(p, 1.0, -2.5, h, 0.1).cell, north);
  // ... past it, the street it turned into, at the arc along it.
  const CellPoint q = m.follow(p, 3.0, -1.8, h, 0.1);
  EXPECT_EQ(q.cell, to_east);
  EXPECT_NEAR(q.arc_m, 3.0, 1e-9);
  // Left turn, outside of the corner: beyond the end, nearest the junction vertex
  // on both streets; heading north-west, it is on the street to the west.
  EXPECT_EQ(m.follow(p, 1.8, 0.5, -h, 0.1).cell, to_west);
  // Going straight on past the end with no street ahead stays on the last one
  // (no successor lies along the way and none is nearer).
  EXPECT_EQ(m.follow(p, 0.3, -0.5, 0, 0.1).cell, north);
  // Past the bisector with the heading still almost north (the turn has barely
  // begun): the cell is decided by distance, the nearest-point rule that defines
  // the truth's cell too; the heading only picks which successor.
  EXPECT_EQ(m.follow(p, 3.0, -1.8, 0.1, 0.1).cell, to_east);
  EXPECT_EQ(m.follow(p, 1.0, -2.5, 0.1, 0.1).cell, north);
}

// A fork whose branches part at 24 degrees: 4 m past it they are 1.7 m apart, so
// the successor taken at the junction (by the heading while the vehicle still
// turned) may be the other branch. Within the first metres of a cell, follow
// weighs the junction's other branches again (distance and heading).
TEST(MapMatcher, FollowTakesTheOtherBranchJustPastAFork) {
  blvd_test::GraphBuilder b;
  const double half = 12 * kPi / 180;
  const uint32_t a = b.vertex(0, -100), j = b.vertex(0, 0);
  const uint32_t r = b.vertex(100 * std::sin(half), 100 * std::cos(half)), l = b.vertex(-100 * std::sin(half), 100 * std::cos(half));
  b.street(a, j);
  const uint32_t right = b.street(j, r), left = b.street(j, l);
  const auto g = b.finish();
  MapMatcher m(g);
  // 5 m along the right branch, heading along it, but following from the left one.
  const double e = 5 * std::sin(half), n = 5 * std::cos(half);
  const CellPoint wrong = m.project(left, e, n);
  ASSERT_EQ(wrong.cell, left);
  ASSERT_GT(wrong.arc_m, 4.0);
  const CellPoint q = m.follow(wrong, e, n, half, 0.02);
  EXPECT_EQ(q.cell, right);
  EXPECT_NEAR(q.arc_m, 5.0, 1e-9);
  // On the left branch, heading along it: stays.
  EXPECT_EQ(m.follow(wrong, -e, n, -half, 0.02).cell, left);
  // Past the first metres the choice is the HMM's (its next step), not follow's.
  const double e2 = 12 * std::sin(half), n2 = 12 * std::cos(half);
  EXPECT_EQ(m.follow(m.project(left, e2, n2), e2, n2, half, 0.02).cell, left);
}

// Every segment within r of (px, py) must be reported by the grid (brute force
// over the graph's two-point streets).
void expectGridFindsAll(const graph::StreetGraph& g, const graph::SegmentGrid& grid, double px, double py, double r) {
  std::set<uint32_t> listed, brute;
  grid.query(px, py, r, [&](const graph::SegmentGrid::Entry& e) { listed.insert(e.halfedge); });
  for (uint32_t h = 0; h < g.halfedges.size(); h += 2) {
    const auto& he = g.halfedges[h];
    const glm::dvec2 a = g.points[he.pts_begin], b = g.points[he.pts_begin + 1];
    const glm::dvec2 d = b - a;
    const double u = std::clamp(((px - a.x) * d.x + (py - a.y) * d.y) / (d.x * d.x + d.y * d.y), 0.0, 1.0);
    if (std::hypot(a.x + d.x * u - px, a.y + d.y * u - py) <= r) brute.insert(h);
  }
  EXPECT_FALSE(brute.empty());
  for (uint32_t h : brute) EXPECT_TRUE(listed.count(h)) << "half-edge " << h;
}

TEST(MapMatcher, GridFindsEverySegmentInReach) {
  const auto g = blvd_test::makeGrid(6, 80);
  graph::SegmentGrid grid;
  grid.build(g, 50);
  EXPECT_GT(grid.entryCount(), 0u);
  EXPECT_EQ(grid.cellSize(), 50.0);  // a town keeps the cell size asked for
  expectGridFindsAll(g, grid, 123, 201, 45);
}

// A package's points may lie up to 10,000 km from its origin: the grid over a
// graph spread that thin takes coarser cells instead of 400,000 x 400,000 of
// 50 m (which a corrupt package once asked for), and still finds every street.
TEST(MapMatcher, GridOverAGraphSpreadAcrossAContinentStaysSmall) {
  blvd_test::GraphBuilder b;
  const uint32_t a = b.vertex(-1e7, -1e7), c = b.vertex(1e7, 1e7), d = b.vertex(1e7, -1e7);
  b.street(a, c);  // one diagonal segment 28,000 km long
  b.street(c, d);
  b.street(d, a);
  const graph::StreetGraph g = b.finish();
  graph::SegmentGrid grid;
  grid.build(g, 50);
  EXPECT_LE(grid.shape().cellCount(), 65536u);
  EXPECT_LE(grid.entryCount(), 16u * 3);
  EXPECT_GT(grid.cellSize(), 50.0);
  expectGridFindsAll(g, grid, 0, 0, 10);
  expectGridFindsAll(g, grid, 1e7 - 5, 0, 10);
  expectGridFindsAll(g, grid, 0, -1e7 + 5, 10);
}

TEST(MapMatcher, StepsDoNotAllocate) {
  const auto g = blvd_test::makeGrid(8, 60);
  MapMatcher m(g);
  m.step(obsAt(0, 30, 0, 5, 90));  // warm-up
  long allocs = 0;
  {
    AllocCounter count;
    for (int i = 1; i < 200; ++i) {
      const double s = i * 7.0;  // east along y = 0, then north along x = 420, ...
      const double e = std::min(s, 420.0), n = std::max(0.0, s - 420.0);
      m.step(obsAt(i, e + 1.5, std::min(n, 420.0), 5, s < 420 ? 90 : 0));
      (void)m.follow(m.head(), e + 2, n, 0, 0.1);
    }
    allocs = count.count();
  }
  EXPECT_EQ(allocs, 0);
  EXPECT_EQ(m.stats().steps, 200u);
}

// The search scratch is sized by the search bounds: a city 16 times larger
// costs the matcher only its spatial index, and the same drive on the corner
// both cities share gives the same answers.
TEST(MapMatcher, ScratchDoesNotGrowWithTheCity) {
  const auto small = blvd_test::makeGrid(8, 60), large = blvd_test::makeGrid(32, 60);
  MapMatcher a(small), b(large);
  EXPECT_EQ(a.bytes() - a.indexBytes(), b.bytes() - b.indexBytes());
  EXPECT_LT(a.indexBytes(), b.indexBytes());
  for (int i = 0; i < 60; ++i) {
    const double e = std::min(i * 7.0, 400.0), n = std::max(0.0, i * 7.0 - 400.0);
    const MatchObservation o = obsAt(i, e + 1.5, n, 5, i * 7.0 < 400 ? 90 : 0);
    ASSERT_EQ(a.step(o), b.step(o));
    // Cell ids differ between the graphs; the matched point does not.
    EXPECT_DOUBLE_EQ(a.head().e, b.head().e) << "step " << i;
    EXPECT_DOUBLE_EQ(a.head().n, b.head().n) << "step " << i;
  }
  EXPECT_EQ(a.stats().candidates_dropped + b.stats().candidates_dropped, 0u);
}

}  // namespace
}  // namespace blvd::track
