// The tracker on the real street graph of the baked Monaco fixture package:
// simulated drives are matched to their cells, with no allocation per update.
// (The full benchmark, with its thresholds, is bench_track / track.bench.)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "fault/alloc_counter.h"
#include "stream/city.h"
#include "track/lane.h"
#include "track/map_matcher.h"
#include "track/sim.h"
#include "track/tracker.h"

namespace blvd::track {
namespace {
constexpr double kPi = 3.14159265358979323846;

class TrackMonaco : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    city_ = new stream::City;
    std::string err;
    ASSERT_EQ(city_->open(BLVD_TEST_PACKAGE, err), core::Status::Ok) << err;
  }
  static void TearDownTestSuite() {
    delete city_;
    city_ = nullptr;
  }
  // A simulated 40-cell drive with 5 m GNSS noise.
  static SimTrace drive(uint64_t seed) {
    SimDesc sd;
    sd.seed = seed;
    sd.route_cells = 40;
    sd.gnss_sigma_m = 5;
    return simulateDrive(city_->graph(), city_->frame(), sd);
  }
  static stream::City* city_;
};
stream::City* TrackMonaco::city_ = nullptr;

TEST_F(TrackMonaco, SimulatedDrivesStayOnTheirCells) {
  size_t epochs = 0, on = 0;
  long allocs = 0;
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    const SimTrace trace = drive(seed);
    ASSERT_FALSE(trace.epochs.empty());
    Tracker tr(city_->frame(), &city_->graph());
    std::unique_ptr<blvd_test::AllocCounter> count;
    size_t fi = 0, oi = 0;
    for (size_t e = 0; e < trace.epochs.size(); ++e) {
      if (e == 5) count = std::make_unique<blvd_test::AllocCounter>();
      const double t = trace.epochs[e].t;
      while (fi < trace.fixes.size() && trace.fixes[fi].t <= t) tr.feedGnss(trace.fixes[fi++]);
      while (oi < trace.odometry.size() && trace.odometry[oi].t <= t) tr.feedOdometry(trace.odometry[oi++]);
      const Pose& p = tr.update(t);
      ++epochs;
      on += p.cell == trace.epochs[e].cell;
    }
    allocs += count ? count->count() : 0;
  }
  EXPECT_GT(static_cast<double>(on) / static_cast<double>(epochs), 0.93) << on << " of " << epochs;
  EXPECT_EQ(allocs, 0);
}

// The tracker over the package's graph read through a page cache far smaller
// than the graph (every update reads across page edges, and pages are evicted
// and read again) gives bit for bit the poses it gives over the whole graph,
// and still allocates nothing per update.
TEST_F(TrackMonaco, PagedGraphTracksAsTheWholeGraph) {
  stream::City paged;
  std::string err;
  ASSERT_EQ(paged.open(BLVD_TEST_PACKAGE, err, stream::City::Tables::Graph, stream::City::GraphTables::Paged,
                       stream::PagedGraphDesc{16, 1024}),
            core::Status::Ok)
      << err;
  size_t epochs = 0;
  long allocs = 0;
  for (uint64_t seed = 1; seed <= 2; ++seed) {
    const SimTrace trace = drive(seed);
    Tracker whole(city_->frame(), &city_->graph()), tiled(paged.frame(), &paged.streets());
    std::unique_ptr<blvd_test::AllocCounter> count;
    size_t fi = 0, oi = 0;
    for (size_t e = 0; e < trace.epochs.size(); ++e) {
      if (e == 5) count = std::make_unique<blvd_test::AllocCounter>();
      const double t = trace.epochs[e].t;
      for (; fi < trace.fixes.size() && trace.fixes[fi].t <= t; ++fi) whole.feedGnss(trace.fixes[fi]), tiled.feedGnss(trace.fixes[fi]);
      for (; oi < trace.odometry.size() && trace.odometry[oi].t <= t; ++oi)
        whole.feedOdometry(trace.odometry[oi]), tiled.feedOdometry(trace.odometry[oi]);
      const Pose a = whole.update(t), b = tiled.update(t);
      ASSERT_EQ(a.cell, b.cell) << "seed " << seed << " epoch " << e;
      ASSERT_EQ(a.arc_m, b.arc_m) << "seed " << seed << " epoch " << e;
      ASSERT_EQ(a.e, b.e);
      ASSERT_EQ(a.n, b.n);
      ++epochs;
    }
    allocs += count ? count->count() : 0;
  }
  EXPECT_GT(epochs, 100u);
  EXPECT_EQ(allocs, 0);
  EXPECT_GT(paged.graphPageStats().misses, 100u);
}

// The simulated car keeps to the lane of lane.h, the lane the map aid expects:
// right of the centre line on two-way streets, the centre of one-way streets.
// Without lane wander, on straight stretches away from junctions (pure pursuit
// cuts corners), its offset from the centre line is the model's.
TEST_F(TrackMonaco, SimulatedCarKeepsToItsLane) {
  const graph::StreetGraph& g = city_->graph();
  const MapMatcher m(g);
  std::vector<double> one_way, two_way;
  for (uint64_t seed = 1; seed <= 8; ++seed) {
    SimDesc sd;
    sd.seed = seed;
    sd.route_cells = 40;
    sd.lane_wander_m = 0;
    const SimTrace trace = simulateDrive(g, city_->frame(), sd);
    for (const SimSample& s : trace.epochs) {
      const auto& he = g.halfedges[s.cell];
      if (s.arc_m < 15 || he.length - s.arc_m < 15) continue;
      const CellPoint q = m.project(s.cell, s.e, s.n);
      const double dh = std::remainder(s.heading_deg * kPi / 180 - q.heading_rad, 2 * kPi);
      if (std::fabs(dh) > 1 * kPi / 180) continue;  // in a curve
      (he.flags & graph::kOneway ? one_way : two_way).push_back(q.lateral_m - laneOffset(he, sd.lateral_m));
    }
  }
  auto medianAbs = [](std::vector<double> v) {
    for (double& x : v) x = std::fabs(x);
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  ASSERT_GT(one_way.size(), 20u);
  ASSERT_GT(two_way.size(), 20u);
  EXPECT_LT(medianAbs(one_way), 0.2);
  EXPECT_LT(medianAbs(two_way), 0.2);
}

}  // namespace
}  // namespace blvd::track
