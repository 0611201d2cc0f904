// The tracker on the real street graph of the baked Monaco fixture package:
// simulated drives are matched to their cells, with no allocation per update.
// (The full benchmark, with its thresholds, is bench_track / track.bench.)
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "fault/alloc_counter.h"
#include "stream/city.h"
#include "track/sim.h"
#include "track/tracker.h"

namespace blvd::track {
namespace {

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
  static stream::City* city_;
};
stream::City* TrackMonaco::city_ = nullptr;

TEST_F(TrackMonaco, SimulatedDrivesStayOnTheirCells) {
  size_t epochs = 0, on = 0;
  long allocs = 0;
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    SimDesc sd;
    sd.seed = seed;
    sd.route_cells = 40;
    sd.gnss_sigma_m = 5;
    const SimTrace trace = simulateDrive(city_->graph(), city_->frame(), sd);
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

}  // namespace
}  // namespace blvd::track
