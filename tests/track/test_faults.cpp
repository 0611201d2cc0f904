// Faults in the middle of a drive (track/sim.h on the grid city): a minute
// without GNSS, a fix 100 m off, fixes out of order, a host clock that goes
// back an hour, fixes at 20 Hz each reported twice. Each time the drive goes
// on, the pose comes back to the truth, and the fault shows in the stats.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "track/sim.h"
#include "track/tracker.h"
#include "sim_replay.h"

namespace blvd::track {
namespace {

const geo::LocalFrame& frame() { return blvd_test::gridFrame(); }
const graph::StreetGraph& grid() { return blvd_test::gridCity(); }

SimDesc faultDesc(uint64_t seed) {
  SimDesc d;
  d.seed = seed;
  d.route_cells = 40;
  d.gnss_sigma_m = 3;
  d.drop_fraction = 0;  // the only gaps are the ones a test makes
  d.outage_s = 0;
  return d;
}

double error(const Pose& p, const SimSample& s) { return std::hypot(p.e - s.e, p.n - s.n); }

// Feeds the odometry up to t, then updates; the caller feeds fixes.
struct Feeder {
  Tracker& tr;
  const SimTrace& trace;
  size_t oi = 0;
  double clock_offset = 0;  // added to every stamp from now on (a host clock that steps)
  void odometryUntil(double t) {
    while (oi < trace.odometry.size() && trace.odometry[oi].t <= t) {
      Odometry o = trace.odometry[oi++];
      o.t += clock_offset;
      tr.feedOdometry(o);
    }
  }
  void fix(GnssFix f) {
    f.t += clock_offset;
    tr.feedGnss(f);
  }
  const Pose& update(double t) { return tr.update(t + clock_offset); }
};

// Share of epochs from `from` on whose matched cell is the true one, and the
// worst position error among them.
struct Recovery {
  size_t epochs = 0, on_cell = 0;
  double worst_m = 0;
  void add(const Pose& p, const SimSample& s) {
    ++epochs;
    on_cell += p.cell == s.cell;
    worst_m = std::max(worst_m, error(p, s));
  }
  double share() const { return epochs ? static_cast<double>(on_cell) / static_cast<double>(epochs) : 0; }
};

TEST(TrackerFaults, AMinuteWithoutGnssIsDeadReckonedAndRecovers) {
  SimDesc d = faultDesc(21);
  d.outage_s = 60;
  d.outage_at = 0.3;
  const SimTrace trace = simulateDrive(grid(), frame(), d);
  ASSERT_GT(trace.outage_begin, 20.0);
  ASSERT_GT(trace.duration_s, trace.outage_end + 60);
  Tracker tr(frame(), &grid());
  Recovery after;
  size_t invalid = 0;
  blvd_test::replaySim(tr, trace, -1e300, [&](size_t e, const Pose& p) {
    const SimSample& s = trace.epochs[e];
    invalid += !(p.flags & kPoseValid);
    if (s.t > trace.outage_begin + 3 && s.t < trace.outage_end) {
      EXPECT_TRUE(p.flags & kPoseDeadReckoning) << "t " << s.t;
      EXPECT_TRUE(p.flags & kPoseMatched) << "t " << s.t;  // still moving along the streets
    }
    if (s.t > trace.outage_end + 10) {
      EXPECT_FALSE(p.flags & kPoseDeadReckoning) << "t " << s.t;
      after.add(p, s);
    }
  });
  EXPECT_EQ(invalid, 0u);
  EXPECT_GT(after.share(), 0.95);
  EXPECT_LT(after.worst_m, 10.0);
  const TrackerStats st = tr.stats();
  EXPECT_EQ(st.outages, 1u);
  EXPECT_NEAR(st.longest_outage_s, trace.outage_end - trace.outage_begin, 1.5);
  EXPECT_EQ(st.clock_steps, 0u);
}

TEST(TrackerFaults, AFix100MetresOffIsGatedOut) {
  const SimTrace trace = simulateDrive(grid(), frame(), faultDesc(22));
  ASSERT_GT(trace.fixes.size(), 100u);
  // Fixes 60, 61 and 62 jump 100 m east (multipath, a bad epoch): fewer than
  // EkfDesc::reset_after_rejects in a row, so the filter keeps its position.
  std::vector<GnssFix> fixes = trace.fixes;
  for (size_t k = 60; k < 63; ++k) {
    double lat = 0, lon = 0, h = 0;
    const geo::Enu p = frame().forward(fixes[k].lat, fixes[k].lon, frame().h0());
    frame().reverse(geo::Enu{p.e + 100, p.n, 0}, lat, lon, h);
    fixes[k].lat = lat;
    fixes[k].lon = lon;
  }
  SimTrace jumped = trace;
  jumped.fixes = fixes;
  Tracker tr(frame(), &grid());
  Recovery all;
  blvd_test::replaySim(tr, jumped, -1e300, [&](size_t e, const Pose& p) {
    if (trace.epochs[e].t > 10) all.add(p, trace.epochs[e]);
  });
  EXPECT_LT(all.worst_m, 10.0);  // never pulled towards the jump
  EXPECT_GT(all.share(), 0.95);
  Tracker clean(frame(), &grid());
  blvd_test::replaySim(clean, trace, -1e300, [](size_t, const Pose&) {});
  const TrackerStats st = tr.stats(), base = clean.stats();
  EXPECT_EQ(st.gnss_rejected, base.gnss_rejected + 3);
  EXPECT_EQ(st.filter_resets, base.filter_resets);
}

TEST(TrackerFaults, FixesOutOfOrderAreLateAndStillUsed) {
  const SimTrace trace = simulateDrive(grid(), frame(), faultDesc(23));
  Tracker tr(frame(), &grid());
  Feeder f{tr, trace};
  Recovery all;
  // Every fifth fix arrives after the next one, in a later update.
  const std::vector<GnssFix>& fx = trace.fixes;
  size_t swapped = 0;
  for (size_t k = 0; k + 1 < fx.size(); ++k) {
    const bool swap = k % 5 == 4;
    const size_t first = swap ? k + 1 : k;
    f.odometryUntil(fx[first].t);
    f.fix(fx[first]);
    const Pose& p = f.update(fx[first].t);
    if (fx[first].t > 10) all.add(p, trace.epochs[first]);
    if (swap) {
      f.fix(fx[k]);
      f.update(fx[k + 1].t);
      ++k;
      ++swapped;
    }
  }
  ASSERT_GT(swapped, 20u);
  EXPECT_GE(tr.stats().late_events, swapped);
  EXPECT_EQ(tr.stats().gnss_used + tr.stats().gnss_rejected, tr.stats().gnss_fed);  // none lost
  EXPECT_LE(tr.stats().gnss_rejected, 2u);
  EXPECT_LT(all.worst_m, 10.0);
  EXPECT_GT(all.share(), 0.95);
}

// Halfway through the drive every stamp moves by `offset` seconds: a host
// clock reset (back), or a clock that jumps ahead; the tracker's statistics.
TrackerStats driveThroughAClockStep(double offset) {
  const SimTrace trace = simulateDrive(grid(), frame(), faultDesc(24));
  Tracker tr(frame(), &grid());
  Feeder f{tr, trace};
  Recovery after;
  size_t invalid_after_step = 0;
  const double step_at = 0.5 * trace.duration_s;
  for (size_t k = 0; k < trace.fixes.size(); ++k) {
    const double t = trace.fixes[k].t;
    if (t >= step_at && f.clock_offset == 0) f.clock_offset = offset;
    f.odometryUntil(t);
    f.fix(trace.fixes[k]);
    const Pose& p = f.update(t);
    if (t < step_at) continue;
    invalid_after_step += !(p.flags & kPoseValid);
    if (t > step_at + 5) after.add(p, trace.epochs[k]);
  }
  EXPECT_EQ(invalid_after_step, 0u);  // the pose never went away
  EXPECT_GT(after.share(), 0.95);
  EXPECT_LT(after.worst_m, 10.0);
  return tr.stats();
}

TEST(TrackerFaults, AHostClockThatGoesBackAnHourRestartsFromThePose) {
  EXPECT_EQ(driveThroughAClockStep(-3600).clock_steps, 1u);
}

// No filter predicts across an hour (nor across 10^18 s of a wild stamp).
TEST(TrackerFaults, AClockThatJumpsAheadAnHourRestartsFromThePose) {
  EXPECT_EQ(driveThroughAClockStep(3600).clock_steps, 1u);
}

TEST(TrackerFaults, FixesAt20HzReportedTwiceCountOnce) {
  SimDesc d = faultDesc(25);
  d.gnss_rate_hz = 20;
  d.route_cells = 15;
  const SimTrace trace = simulateDrive(grid(), frame(), d);
  // Once each, then each fix fed again after itself; every third is updated
  // in between (in both), so its repeat arrives in a later update.
  Tracker once(frame(), &grid()), twice(frame(), &grid());
  Feeder fo{once, trace}, ft{twice, trace};
  Recovery all;
  for (size_t k = 0; k < trace.fixes.size(); ++k) {
    const double t = trace.fixes[k].t;
    fo.odometryUntil(t);
    fo.fix(trace.fixes[k]);
    ft.odometryUntil(t);
    ft.fix(trace.fixes[k]);
    if (k % 3 == 0) {
      fo.update(t);
      ft.update(t);
    }
    ft.fix(trace.fixes[k]);
    const Pose a = fo.update(t);
    const Pose b = ft.update(t);
    ASSERT_EQ(a.e, b.e) << "fix " << k;  // bit for bit: the repeat changed nothing
    ASSERT_EQ(a.n, b.n) << "fix " << k;
    ASSERT_EQ(a.pos_sigma_m, b.pos_sigma_m) << "fix " << k;
    ASSERT_EQ(a.cell, b.cell) << "fix " << k;
    if (t > 10) all.add(b, trace.epochs[k]);
  }
  EXPECT_EQ(twice.stats().gnss_duplicates, trace.fixes.size());
  EXPECT_EQ(once.stats().gnss_duplicates, 0u);
  EXPECT_EQ(twice.stats().gnss_used, once.stats().gnss_used);
  EXPECT_LT(all.worst_m, 10.0);
  EXPECT_GT(all.share(), 0.95);
}

// A repeat that completes its epoch: the first report has no speed or course,
// the second has them. The position counts once and the speed and course are
// used: the same filter as one complete report (GNSS alone).
TEST(TrackerFaults, ARepeatAddsWhatTheFirstReportLacked) {
  const SimTrace trace = simulateDrive(grid(), frame(), faultDesc(26));
  Tracker split(frame(), &grid()), whole(frame(), &grid()), bare_only(frame(), &grid());
  double without_speed = 0;
  for (size_t k = 0; k < 60; ++k) {
    GnssFix bare = trace.fixes[k];
    bare.flags &= ~(kGnssHasSpeed | kGnssHasTrack);
    split.feedGnss(bare);
    split.feedGnss(trace.fixes[k]);
    whole.feedGnss(trace.fixes[k]);
    bare_only.feedGnss(bare);
    bare_only.feedGnss(bare);
    const double t = bare.t;
    const Pose a = split.update(t), b = whole.update(t), c = bare_only.update(t);
    // The same, but for rounding: the split epoch's HMM step comes between
    // its position and its course instead of after both.
    ASSERT_NEAR(a.e, b.e, 1e-3) << "fix " << k;
    ASSERT_NEAR(a.n, b.n, 1e-3) << "fix " << k;
    ASSERT_NEAR(std::remainder(a.heading_deg - b.heading_deg, 360.0), 0.0, 1e-3) << "fix " << k;
    ASSERT_NEAR(a.speed_mps, b.speed_mps, 1e-3) << "fix " << k;
    without_speed = std::max(without_speed, std::fabs(c.speed_mps - b.speed_mps));
  }
  EXPECT_GT(without_speed, 1.0);  // without the repeat's speed and course the filter differs
  EXPECT_EQ(split.stats().gnss_duplicates, 60u);
  EXPECT_EQ(bare_only.stats().gnss_duplicates, 60u);
  EXPECT_EQ(whole.stats().gnss_duplicates, 0u);
}

}  // namespace
}  // namespace blvd::track
