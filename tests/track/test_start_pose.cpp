// Starting a drive from the pose kept at the end of the previous one
// (Tracker::setStartPose): a matched pose before the first fix and dead
// reckoning out of a garage without GNSS, a car moved while it was parked found
// by its fixes, refused input; and the simulator's chained drives that
// `blvd bench track` measures it on (on_cell_sigma5_chained / _resumed).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "track/sim.h"
#include "track/tracker.h"
#include "sim_replay.h"
#include "track_test_util.h"

namespace blvd::track {
namespace {

const geo::LocalFrame& frame() { return blvd_test::gridFrame(); }
const graph::StreetGraph& grid() { return blvd_test::gridCity(); }

// A drive that pulls away from a standstill, as one after a stop does.
SimDesc parkedStart(uint64_t seed) {
  SimDesc d;
  d.seed = seed;
  d.route_cells = 30;
  d.start_speed_mps = 0;
  return d;
}

StartPose startAt(double t, double e, double n, double heading_deg, double sigma_m, double heading_sigma_deg) {
  StartPose sp;
  double h = 0;
  frame().reverse(geo::Enu{e, n, 0}, sp.lat, sp.lon, h);
  sp.t = t;
  sp.heading_deg = heading_deg;
  sp.sigma_m = sigma_m;
  sp.heading_sigma_deg = heading_sigma_deg;
  return sp;
}

TEST(StartPose, ChainedDriveStartsWhereTheLastOneParked) {
  SimDesc a = parkedStart(3);
  a.park_mid_last_cell = true;
  const SimTrace ta = simulateDrive(grid(), frame(), a);
  ASSERT_GT(ta.epochs.size(), 30u);
  EXPECT_EQ(ta.end_cell, ta.route.back());
  EXPECT_NEAR(ta.end_arc_m, 0.5 * grid().halfedges[ta.end_cell].length, 1.5);  // parked halfway along it
  // Drives that do not park run to the route's end.
  const SimTrace full = simulateDrive(grid(), frame(), parkedStart(3));
  EXPECT_GT(full.end_arc_m, grid().halfedges[full.end_cell].length - 2.0);

  SimDesc b = parkedStart(4);
  b.first_cell = ta.end_cell;
  b.start_arc_m = ta.end_arc_m;
  const SimTrace tb = simulateDrive(grid(), frame(), b);
  ASSERT_FALSE(tb.epochs.empty());
  EXPECT_EQ(tb.route.front(), ta.end_cell);
  EXPECT_LT(std::hypot(tb.start_e - ta.end_e, tb.start_n - ta.end_n), 1.5);  // the lane wander is drawn afresh
  EXPECT_NEAR(std::remainder(tb.start_heading_deg - ta.end_heading_deg, 360.0), 0.0, 10.0);
  const SimSample& s = tb.epochs.front();  // t = 1 s: pulling away at 1.5 m/s^2
  EXPECT_EQ(s.cell, ta.end_cell);
  EXPECT_GT(s.arc_m, ta.end_arc_m + 0.3);
  EXPECT_LT(s.arc_m, ta.end_arc_m + 1.2);
  EXPECT_LE(s.speed_mps, 1.5 + 1e-9);
}

TEST(StartPose, MatchedBeforeTheFirstFixAndOutOfAGarage) {
  // No GNSS for the first 30 s (an underground car park); odometry all along.
  const SimTrace trace = simulateDrive(grid(), frame(), parkedStart(7));
  ASSERT_GT(trace.epochs.size(), 60u);
  constexpr double kFirstFix = 30;
  // A host that keeps the pose also keeps the odometry calibration.
  OdometryCalibration cal;
  cal.speed_scale = SimDesc{}.speed_scale;
  cal.yaw_bias_rad_s = SimDesc{}.yaw_bias_dps * 3.14159265358979323846 / 180;

  Tracker resumed(frame(), &grid()), cold(frame(), &grid());
  ASSERT_TRUE(resumed.setCalibration(cal));
  ASSERT_TRUE(cold.setCalibration(cal));
  // The stored pose is off by 0.5 m and 1 degree, as a fused pose at key-off is.
  ASSERT_TRUE(resumed.setStartPose(startAt(0, trace.start_e + 0.3, trace.start_n - 0.4, trace.start_heading_deg + 1, 0.5, 1)));
  const Pose& p0 = resumed.update(0);
  ASSERT_TRUE(p0.flags & kPoseValid);
  ASSERT_TRUE(p0.flags & kPoseMatched);
  EXPECT_TRUE(p0.flags & kPoseDeadReckoning);  // no fix yet
  EXPECT_TRUE(p0.flags & kPoseHeadingValid);
  EXPECT_EQ(p0.cell, trace.route.front());
  EXPECT_NEAR(p0.pos_sigma_m, 0.5, 1e-9);
  EXPECT_NEAR(p0.heading_sigma_deg, 1.0, 1e-9);

  size_t garage = 0, on = 0, cold_valid = 0;
  double worst = 0;
  blvd_test::replaySim(resumed, trace, kFirstFix, [&](size_t e, const Pose& p) {
    const SimSample& s = trace.epochs[e];
    if (s.t >= kFirstFix) return;
    ++garage;
    on += p.cell == s.cell;
    worst = std::max(worst, std::hypot(p.e - s.e, p.n - s.n));
  });
  blvd_test::replaySim(cold, trace, kFirstFix, [&](size_t e, const Pose& p) {
    if (trace.epochs[e].t < kFirstFix) cold_valid += (p.flags & kPoseValid) != 0;
  });
  ASSERT_GT(garage, 25u);
  EXPECT_GE(static_cast<double>(on) / static_cast<double>(garage), 0.9) << on << " of " << garage;
  EXPECT_LT(worst, 5.0);
  EXPECT_EQ(cold_valid, 0u);  // without the stored pose there is nothing to show until the first fix
}

TEST(StartPose, ACarMovedWhileParkedIsFoundByItsFixes) {
  const SimTrace trace = simulateDrive(grid(), frame(), parkedStart(9));
  ASSERT_GT(trace.epochs.size(), 60u);
  Tracker tr(frame(), &grid());
  // Parked, then towed 2 blocks away: the stored pose is 140 m off.
  ASSERT_TRUE(tr.setStartPose(startAt(0, trace.start_e + 140, trace.start_n, trace.start_heading_deg, 0.5, 1)));
  size_t late = 0, on = 0;
  blvd_test::replaySim(tr, trace, 0, [&](size_t e, const Pose& p) {
    const SimSample& s = trace.epochs[e];
    if (s.t < 20) return;
    ++late;
    on += p.cell == s.cell;
    EXPECT_LT(std::hypot(p.e - s.e, p.n - s.n), 15.0) << "t " << s.t;
  });
  EXPECT_GE(tr.stats().filter_resets, 1u);  // the fixes were believed over the stored pose
  ASSERT_GT(late, 20u);
  EXPECT_GE(static_cast<double>(on) / static_cast<double>(late), 0.9) << on << " of " << late;
}

TEST(StartPose, RefusesAnImpossibleOneAndChangesNothing) {
  const SimTrace trace = simulateDrive(grid(), frame(), parkedStart(7));
  Tracker tr(frame(), &grid());
  const StartPose good = startAt(0, trace.start_e, trace.start_n, trace.start_heading_deg, 0, 0);
  ASSERT_TRUE(tr.setStartPose(good));
  const Pose before = tr.update(0);
  EXPECT_NEAR(before.pos_sigma_m, kStartSigmaDefaultM, 1e-9);  // 0: the defaults
  EXPECT_NEAR(before.heading_sigma_deg, kStartHeadingSigmaDefaultDeg, 1e-9);
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  StartPose bad[8] = {good, good, good, good, good, good, good, good};
  bad[0].lat = nan;
  bad[1].lat = 90.5;
  bad[2].lon = -180.5;
  bad[3].sigma_m = -1;
  bad[4].heading_sigma_deg = -0.1;
  bad[5].heading_deg = inf;
  bad[6].t = nan;
  bad[7].sigma_m = inf;
  for (const StartPose& b : bad) EXPECT_FALSE(tr.setStartPose(b));
  const Pose after = tr.update(0);
  EXPECT_EQ(after.e, before.e);
  EXPECT_EQ(after.n, before.n);
  EXPECT_EQ(after.cell, before.cell);
  // Small sigmas are raised to the floors.
  StartPose sharp = good;
  sharp.sigma_m = 0.01;
  sharp.heading_sigma_deg = 0.01;
  ASSERT_TRUE(tr.setStartPose(sharp));
  EXPECT_NEAR(tr.update(0).pos_sigma_m, kStartSigmaMinM, 1e-9);
  EXPECT_NEAR(tr.pose().heading_sigma_deg, kStartHeadingSigmaMinDeg, 1e-9);
}

}  // namespace
}  // namespace blvd::track
