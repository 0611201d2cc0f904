// The Tracker end to end on a synthetic grid city (track/sim.h drives): the
// matched cell, zero heap allocations per feed and update after construction,
// bit-identical output for identical input, feeds from several threads, the
// ring's overflow policy, fusion without a map, bad input, and the map aid
// beside a parallel street.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <memory>
#include <random>
#include <thread>
#include <vector>

#include "fault/alloc_counter.h"
#include "track/sim.h"
#include "track/tracker.h"
#include "sim_replay.h"
#include "track_test_util.h"

namespace blvd::track {
namespace {

using blvd_test::AllocCounter;

const geo::LocalFrame& frame() { return blvd_test::gridFrame(); }
const graph::StreetGraph& grid() { return blvd_test::gridCity(); }

SimDesc simDesc(uint64_t seed, double sigma) {
  SimDesc d;
  d.seed = seed;
  d.route_cells = 30;
  d.gnss_sigma_m = sigma;
  return d;
}

// Every fix, in time order (sim_replay.h).
template <class Fn>
void replay(Tracker& tr, const SimTrace& trace, Fn&& fn) {
  blvd_test::replaySim(tr, trace, -1e300, fn);
}

TEST(Tracker, MatchesASimulatedDriveOnAGrid) {
  const SimTrace trace = simulateDrive(grid(), frame(), simDesc(3, 5));
  ASSERT_GT(trace.epochs.size(), 60u);
  ASSERT_GT(trace.outage_end, trace.outage_begin);
  Tracker tr(frame(), &grid());
  size_t on = 0;
  double worst = 0;
  replay(tr, trace, [&](size_t e, const Pose& p) {
    const SimSample& s = trace.epochs[e];
    ASSERT_TRUE(p.flags & kPoseValid);
    on += p.cell == s.cell;
    if (s.t > 10) worst = std::max(worst, std::hypot(p.e - s.e, p.n - s.n));
    if (p.cell != kNoCell) {
      EXPECT_TRUE(p.flags & kPoseMatched);
      EXPECT_GE(p.confidence, 0.0);
      EXPECT_LE(p.confidence, 1.0);
      // The camera sits on the matched street at eye height, looking along the fused heading.
      EXPECT_DOUBLE_EQ(p.camera.eye_u, 1.5);
      EXPECT_DOUBLE_EQ(p.camera.heading_deg, p.heading_deg);
    }
    if (s.t > trace.outage_begin + 4 && s.t < trace.outage_end) {
      EXPECT_TRUE(p.flags & kPoseDeadReckoning);
    }
  });
  const double share = static_cast<double>(on) / static_cast<double>(trace.epochs.size());
  EXPECT_GT(share, 0.9);
  EXPECT_LT(worst, 15.0);  // through a 20 s outage, 10 % dropped fixes, sigma 5 m
  const TrackerStats st = tr.stats();
  EXPECT_EQ(st.gnss_fed, trace.fixes.size());
  size_t odo_until_last_epoch = 0;
  for (const auto& o : trace.odometry) odo_until_last_epoch += o.t <= trace.epochs.back().t;
  EXPECT_EQ(st.odometry_fed, odo_until_last_epoch);
  EXPECT_EQ(st.ring_dropped, 0u);
  EXPECT_GT(st.match.steps, trace.fixes.size());  // outage epochs are matched on dead reckoning
}

TEST(Tracker, NoAllocationPerFeedOrUpdateAfterWarmUp) {
  const SimTrace trace = simulateDrive(grid(), frame(), simDesc(5, 5));
  Tracker tr(frame(), &grid());
  long during = -1;
  {
    std::unique_ptr<AllocCounter> count;
    replay(tr, trace, [&](size_t e, const Pose&) {
      if (e == 5) count = std::make_unique<AllocCounter>();  // warm-up: 5 s
    });
    during = count->count();
  }
  EXPECT_EQ(during, 0);
  EXPECT_GT(tr.stats().match.steps, 50u);
  EXPECT_GT(tr.bytes(), 0u);
}

TEST(Tracker, SameInputSameOutput) {
  const SimTrace trace = simulateDrive(grid(), frame(), simDesc(11, 15));
  // The simulator itself is deterministic ...
  const SimTrace again = simulateDrive(grid(), frame(), simDesc(11, 15));
  ASSERT_EQ(trace.fixes.size(), again.fixes.size());
  ASSERT_EQ(0, std::memcmp(trace.fixes.data(), again.fixes.data(), trace.fixes.size() * sizeof(GnssFix)));
  // ... and so is the tracker, bit for bit.
  std::vector<Pose> a, b;
  Tracker ta(frame(), &grid()), tb(frame(), &grid());
  replay(ta, trace, [&](size_t, const Pose& p) { a.push_back(p); });
  replay(tb, again, [&](size_t, const Pose& p) { b.push_back(p); });
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].cell, b[i].cell);
    EXPECT_EQ(0, std::memcmp(&a[i].e, &b[i].e, sizeof(double)));
    EXPECT_EQ(0, std::memcmp(&a[i].n, &b[i].n, sizeof(double)));
    EXPECT_EQ(0, std::memcmp(&a[i].confidence, &b[i].confidence, sizeof(double)));
    EXPECT_EQ(0, std::memcmp(&a[i].camera, &b[i].camera, sizeof(CameraPose)));
  }
  // reset() gives a fresh tracker: the same poses again.
  ta.reset();
  std::vector<Pose> c;
  replay(ta, trace, [&](size_t, const Pose& p) { c.push_back(p); });
  ASSERT_EQ(c.size(), a.size());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ(0, std::memcmp(&a[i].e, &c[i].e, sizeof(double)));
}

TEST(Tracker, FeedsFromSeveralThreads) {
  const SimTrace trace = simulateDrive(grid(), frame(), simDesc(13, 5));
  TrackerDesc desc;
  desc.ring_capacity = 1u << 16;  // nothing dropped: the consumer may lag
  Tracker tr(frame(), &grid(), desc);
  std::atomic<bool> done{false};
  std::thread gnss([&] {
    for (const auto& f : trace.fixes) tr.feedGnss(f);
  });
  std::thread odo([&] {
    for (const auto& o : trace.odometry) tr.feedOdometry(o);
  });
  std::thread consumer([&] {
    while (!done.load()) tr.update(0);
  });
  gnss.join();
  odo.join();
  done = true;
  consumer.join();
  const Pose& p = tr.update(trace.epochs.back().t);
  const TrackerStats st = tr.stats();
  EXPECT_EQ(st.gnss_fed, trace.fixes.size());
  EXPECT_EQ(st.odometry_fed, trace.odometry.size());
  EXPECT_EQ(st.ring_dropped, 0u);
  EXPECT_TRUE(p.flags & kPoseValid);
}

TEST(Tracker, FullRingDropsTheOldest) {
  TrackerDesc desc;
  desc.ring_capacity = 8;
  Tracker tr(frame(), nullptr, desc);
  Odometry o;
  o.flags = kOdoSpeed;
  int refused = 0;
  for (int i = 0; i < 20; ++i) {
    o.t = i * 0.01;
    refused += !tr.feedOdometry(o);
  }
  EXPECT_EQ(refused, 12);
  EXPECT_EQ(tr.stats().ring_dropped, 12u);
  EXPECT_EQ(tr.stats().ring_high_water, 8u);
}

TEST(Tracker, FusionWithoutAMapAndBadInput) {
  Tracker tr(frame(), nullptr);
  EXPECT_FALSE(tr.update(0).flags & kPoseValid);
  GnssFix f;
  f.t = 1;
  f.lat = 43.7384;
  f.lon = 7.4246;
  f.flags = kGnssHasLatLon | kGnssHasHAcc;
  f.h_acc_m = 2;
  f.mode = kGnssModeNoFix;
  tr.feedGnss(f);  // the receiver says no fix
  f.mode = kGnssMode3D;
  f.lat = NAN;
  tr.feedGnss(f);  // not a number
  f.lat = 95;
  tr.feedGnss(f);  // out of range
  f.lat = 43.7384;
  f.flags = kGnssHasHAcc;
  tr.feedGnss(f);  // no position
  EXPECT_FALSE(tr.update(1).flags & kPoseValid);
  EXPECT_EQ(tr.stats().gnss_ignored, 4u);
  f.flags = kGnssHasLatLon | kGnssHasHAcc;
  tr.feedGnss(f);
  const Pose& p = tr.update(1);
  EXPECT_TRUE(p.flags & kPoseValid);
  EXPECT_FALSE(p.flags & kPoseMatched);
  EXPECT_EQ(p.cell, kNoCell);
  EXPECT_NEAR(p.e, 0, 1e-6);  // the frame's origin
  EXPECT_NEAR(p.n, 0, 1e-6);
  EXPECT_DOUBLE_EQ(p.camera.eye_e, p.e);
}

// Drives east for 90 s at 10 m/s in the lane of a long two-way street along
// y = 0 (1.75 m right of its centre), beside a parallel street `gap` metres to
// the north, with fixes of sigma 5 m per axis (seeded, Box-Muller) and exact
// odometry; returns the tracker's statistics.
TrackerStats driveBesideAParallelStreet(double gap) {
  blvd_test::GraphBuilder b;
  const uint32_t a0 = b.vertex(-100, 0), a1 = b.vertex(1500, 0);
  const uint32_t b0 = b.vertex(-100, gap), b1 = b.vertex(1500, gap);
  b.street(a0, a1);
  b.street(b0, b1);
  const graph::StreetGraph g = b.finish();
  Tracker tr(frame(), &g);
  std::mt19937_64 rng(7);
  const auto uniform = [&] { return (static_cast<double>(rng() >> 11) + 0.5) * (1.0 / 9007199254740992.0); };
  const auto gauss = [&] { return std::sqrt(-2 * std::log(uniform())) * std::cos(2 * 3.14159265358979323846 * uniform()); };
  const double v = 10, y = -1.75, sigma = 5;
  for (int k = 0; k <= 90 * 50; ++k) {
    const double t = k * 0.02;
    Odometry o;
    o.t = t;
    o.speed_mps = v;
    o.flags = kOdoSpeed | kOdoYawRate;
    tr.feedOdometry(o);
    if (k > 0 && k % 50 == 0) {
      GnssFix f;
      f.t = t;
      double h = 0;
      frame().reverse(geo::Enu{v * t + sigma * gauss(), y + sigma * gauss(), 0}, f.lat, f.lon, h);
      f.speed_mps = static_cast<float>(v);
      f.track_deg = 90;
      f.h_acc_m = static_cast<float>(sigma * std::sqrt(2.0));
      f.mode = kGnssMode3D;
      f.flags = kGnssHasLatLon | kGnssHasHAcc | kGnssHasSpeed | kGnssHasTrack;
      tr.feedGnss(f);
      tr.update(t);
    }
  }
  return tr.stats();
}

TEST(Tracker, MapAidBesideAParallelStreetOnceTheFixesTellThemApart) {
  // 12 m apart: within 2.5 single-fix sigmas (12.5 m), but the mean of the
  // fixes' offsets (sigma 5 / sqrt(n), 1.7 m in the exponential mean's steady
  // state) tells the streets apart within a few fixes: the aid is on for most
  // of the drive.
  const TrackerStats apart = driveBesideAParallelStreet(12);
  EXPECT_GT(apart.map_aids, apart.match.steps / 2);
  EXPECT_LT(apart.map_aid_ambiguous, apart.match.steps / 4);
  // 3 m apart the fixes' mean seldom separates them (only when its noise
  // takes it 2.5 sigmas from the other street): the aid stays off most of the drive.
  const TrackerStats close = driveBesideAParallelStreet(3);
  EXPECT_LT(close.map_aids, close.match.steps / 4);
  EXPECT_GT(close.map_aid_ambiguous + close.map_aid_low_confidence, close.match.steps / 2);
}

TEST(Tracker, WheelSpeedsAloneDriveDeadReckoning) {
  // Odometry with only wheel speeds (no speed signal, no yaw rate): speed from
  // their mean, yaw rate from the rear axle's difference.
  Tracker tr(frame(), nullptr);
  GnssFix f;
  f.lat = 43.7384;
  f.lon = 7.4246;
  f.flags = kGnssHasLatLon | kGnssHasHAcc | kGnssHasSpeed | kGnssHasTrack;
  f.h_acc_m = 1;
  f.speed_mps = 10;
  f.track_deg = 90;  // east
  f.mode = kGnssMode3D;
  tr.feedGnss(f);
  const double r = 50, v = 10, track = 1.6;  // a left turn of radius 50 m
  Odometry o;
  o.flags = kOdoWheelSpeeds;
  for (int i = 1; i <= 100; ++i) {
    o.t = i * 0.02;
    const double w = v / r;
    o.wheel_speeds_mps[0] = o.wheel_speeds_mps[2] = v - w * track / 2;
    o.wheel_speeds_mps[1] = o.wheel_speeds_mps[3] = v + w * track / 2;
    tr.feedOdometry(o);
  }
  const Pose& p = tr.update(2.0);
  EXPECT_NEAR(p.speed_mps, 10, 0.3);
  // 2 s at 10 m/s on a 50 m radius turns 0.4 rad to the left: heading 90 - 22.9 deg.
  EXPECT_NEAR(p.heading_deg, 90 - 22.9, 2.0);
}

}  // namespace
}  // namespace blvd::track
