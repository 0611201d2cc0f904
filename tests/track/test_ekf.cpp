// The EKF on synthetic motion with a known answer: a straight drive and a
// turning drive (with a yaw-rate bias and an odometry scale error to learn), a
// GNSS outage bridged by dead reckoning, outlier gating, a reset after a jump,
// accuracy weighting, and the adaptive sigma for fixes without accuracy.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "track/ekf.h"

namespace blvd::track {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

class Gauss {
 public:
  explicit Gauss(uint64_t seed) : g_(seed) {}
  double operator()() {
    const double u1 = std::max(1e-300, static_cast<double>(g_() >> 11) / 9007199254740992.0);
    const double u2 = static_cast<double>(g_() >> 11) / 9007199254740992.0;
    return std::sqrt(-2 * std::log(u1)) * std::cos(2 * kPi * u2);
  }

 private:
  std::mt19937_64 g_;
};

struct Truth {
  double e = 0, n = 0, psi = 0, v = 0;
};

struct DriveSpec {
  double duration = 120;
  double v = 12;                     // m/s
  double turn_dps = 0;               // true yaw rate (positive left), deg/s
  double gnss_sigma = 3;             // per axis
  double gnss_period = 1.0;
  double outage_begin = 1e9, outage_end = 1e9;
  double yaw_bias_dps = 0;           // added to the measured yaw rate
  double speed_scale = 1.0;          // odometry reads v * scale
  bool gnss_speed = true;
  bool report_sigma = true;          // pass the sigma to the filter (else: unknown)
  uint64_t seed = 7;
};

struct DriveResult {
  std::vector<double> t, err, sigma;
  double distance_outage = 0;
  double err_at_outage_end = 0;
  Ekf ekf;
};

DriveResult drive(const DriveSpec& s, const EkfDesc& desc = EkfDesc{}, const OdometryCalibration* cal = nullptr) {
  DriveResult r;
  r.ekf = Ekf(desc);
  if (cal) {
    EXPECT_TRUE(r.ekf.setCalibration(*cal));
  }
  Gauss noise(s.seed);
  Truth x;
  x.psi = 30 * kDeg;
  x.v = s.v;
  const double dt = 0.02;
  double next_fix = 0;
  for (int k = 0; k * dt <= s.duration; ++k) {
    const double t = k * dt;
    // Odometry at 50 Hz.
    r.ekf.predict(t);
    r.ekf.setYawRate(t, (s.turn_dps + s.yaw_bias_dps) * kDeg + 0.1 * kDeg * noise());
    r.ekf.updateOdometrySpeed(x.v * s.speed_scale + 0.03 * noise(), 0.1);
    if (t + 1e-9 >= next_fix) {
      next_fix += s.gnss_period;
      const bool outage = t >= s.outage_begin && t < s.outage_end;
      if (!outage) {
        // One draw per statement: the order of a call's arguments is unspecified
        // (GCC draws them in another order on arm64), and the drive must be the same everywhere.
        const double noise_n = noise();
        const double noise_e = noise();
        r.ekf.updatePosition(t, x.e + s.gnss_sigma * noise_e, x.n + s.gnss_sigma * noise_n,
                             s.report_sigma ? s.gnss_sigma : 0.0);
        if (s.gnss_speed) {
          const double ve = x.v * std::sin(x.psi) + 0.2 * noise(), vn = x.v * std::cos(x.psi) + 0.2 * noise();
          r.ekf.updateSpeed(std::hypot(ve, vn), 0.3);
          if (std::hypot(ve, vn) > 3) r.ekf.updateHeading(std::atan2(ve, vn), std::atan2(0.3, x.v) + 0.5 * kDeg);
        }
      }
      r.t.push_back(t);
      r.err.push_back(std::hypot(r.ekf.e() - x.e, r.ekf.n() - x.n));
      r.sigma.push_back(r.ekf.positionSigma());
      if (outage && t + s.gnss_period >= s.outage_end) r.err_at_outage_end = r.err.back();
    }
    // Move the truth (same midpoint integration as the filter; compass heading).
    const double psidot = -s.turn_dps * kDeg;
    const double psim = x.psi + 0.5 * psidot * dt;
    x.e += x.v * dt * std::sin(psim);
    x.n += x.v * dt * std::cos(psim);
    x.psi += psidot * dt;
    if (t >= s.outage_begin && t < s.outage_end) r.distance_outage += x.v * dt;
  }
  return r;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

std::vector<double> window(const DriveResult& r, const std::vector<double>& v, double t0, double t1) {
  std::vector<double> out;
  for (size_t i = 0; i < r.t.size(); ++i)
    if (r.t[i] >= t0 && r.t[i] < t1) out.push_back(v[i]);
  return out;
}

TEST(Ekf, StraightDriveErrorShrinksBelowTheFixNoise) {
  DriveSpec s;
  const DriveResult r = drive(s);
  ASSERT_TRUE(r.ekf.initialized());
  ASSERT_TRUE(r.ekf.headingValid());
  const double early = median(window(r, r.err, 0, 10));
  const double late = median(window(r, r.err, 60, 121));
  // A single fix is off by ~1.18 sigma (the median of a 2D Gaussian); the filter averages many.
  EXPECT_LT(late, 0.6 * 1.18 * s.gnss_sigma) << "early " << early;
  EXPECT_LT(late, early);
  // The filter's own sigma shrinks and is of the size of its error.
  EXPECT_LT(window(r, r.sigma, 60, 121).back(), window(r, r.sigma, 0, 3).front());
  EXPECT_NEAR(r.ekf.heading(), 30 * kDeg, 1.5 * kDeg);
  EXPECT_NEAR(r.ekf.speed(), 12.0, 0.2);
}

// Four minutes on a circle of radius v / omega = 86 m, the gyro reading 0.5 deg/s
// too much to the left and the wheels `speed_scale` x the ground speed.
DriveSpec circling(double speed_scale) {
  DriveSpec s;
  s.turn_dps = 8;
  s.yaw_bias_dps = 0.5;
  s.speed_scale = speed_scale;
  s.duration = 240;
  return s;
}

TEST(Ekf, TurningDriveLearnsYawBiasAndOdometryScale) {
  const DriveSpec s = circling(0.98);  // the wheels read 2 % slow
  const DriveResult r = drive(s);
  EXPECT_NEAR(r.ekf.bias(), 0.5 * kDeg, 0.1 * kDeg);
  EXPECT_NEAR(r.ekf.odometryScale(), 0.98, 0.005);
  EXPECT_LT(median(window(r, r.err, 120, 241)), 0.6 * 1.18 * s.gnss_sigma);
}

TEST(Ekf, SurvivesAnOutageOnDeadReckoning) {
  DriveSpec s;
  s.turn_dps = 3;
  s.yaw_bias_dps = 0.3;
  s.speed_scale = 1.02;
  s.duration = 200;
  s.outage_begin = 120;
  s.outage_end = 150;
  const DriveResult r = drive(s);
  // Prediction only: the covariance grows through the outage ...
  const auto sig = window(r, r.sigma, 119, 151);
  EXPECT_GT(sig.back(), 2 * sig.front());
  // ... the error stays within 2 % of the distance driven (bias and scale were learnt before) ...
  EXPECT_LT(r.err_at_outage_end, 0.02 * r.distance_outage) << r.err_at_outage_end << " m over " << r.distance_outage;
  // ... and the fixes bring it back afterwards, without a reset.
  EXPECT_LT(median(window(r, r.err, 170, 201)), 0.6 * 1.18 * s.gnss_sigma);
  EXPECT_EQ(r.ekf.resets(), 0u);
}

// The odometry calibration belongs to the car: a drive that starts from the
// scale and bias the previous drive learnt dead-reckons an early outage
// with the accuracy of a calibrated car; a cold start has had 15 s of fixes to
// learn them.
TEST(Ekf, StartsFromTheCalibrationOfThePreviousDrive) {
  const DriveSpec first = circling(0.97);
  const DriveResult learnt = drive(first);
  const OdometryCalibration cal = learnt.ekf.calibration();
  EXPECT_NEAR(cal.speed_scale, 0.97, 0.005);
  EXPECT_NEAR(cal.yaw_bias_rad_s, 0.5 * kDeg, 0.1 * kDeg);
  EXPECT_GT(cal.speed_scale_sigma, 0);
  EXPECT_LT(cal.speed_scale_sigma, 0.005);

  DriveSpec next = first;
  next.seed = 8;
  next.turn_dps = 3;
  next.duration = 80;
  next.outage_begin = 15;
  next.outage_end = 75;
  const DriveResult cold = drive(next);
  const DriveResult warm = drive(next, EkfDesc{}, &cal);
  EXPECT_NEAR(warm.ekf.odometryScale(), 0.97, 0.003);
  // 60 s on dead reckoning, 720 m: the cold filter carries the scale and bias errors of what
  // 15 s of fixes taught it (when written: 3.3 m warm, 11.2 m cold).
  EXPECT_LT(warm.err_at_outage_end, 0.01 * warm.distance_outage) << warm.err_at_outage_end << " m";
  EXPECT_LT(warm.err_at_outage_end, 0.5 * cold.err_at_outage_end)
      << "warm " << warm.err_at_outage_end << " m, cold " << cold.err_at_outage_end << " m";
}

TEST(Ekf, CalibrationIsAPriorWithFloorsAndSurvivesAReset) {
  Ekf f;
  // Before the first fix: the defaults (scale 1 +- 5 %, bias 0 +- 1 deg/s).
  OdometryCalibration c = f.calibration();
  EXPECT_EQ(c.speed_scale, 1.0);
  EXPECT_NEAR(c.speed_scale_sigma, 0.05, 1e-12);
  EXPECT_EQ(c.yaw_bias_rad_s, 0.0);
  EXPECT_NEAR(c.yaw_bias_sigma_rad_s, 1 * kDeg, 1e-12);

  OdometryCalibration in;
  in.speed_scale = 1.02;
  in.speed_scale_sigma = 1e-4;  // below the floor
  in.yaw_bias_rad_s = 0.3 * kDeg;
  in.yaw_bias_sigma_rad_s = 0;
  ASSERT_TRUE(f.setCalibration(in));
  c = f.calibration();
  EXPECT_EQ(c.speed_scale, 1.02);
  EXPECT_EQ(c.speed_scale_sigma, kMinScaleSigma);
  EXPECT_EQ(c.yaw_bias_sigma_rad_s, kMinYawBiasSigmaRadS);
  // The first fix starts the filter from it ...
  ASSERT_TRUE(f.updatePosition(0, 10, 20, 3));
  EXPECT_EQ(f.odometryScale(), 1.02);
  EXPECT_EQ(f.bias(), 0.3 * kDeg);
  EXPECT_NEAR(std::sqrt(f.cov(Ekf::kK, Ekf::kK)), kMinScaleSigma, 1e-12);
  // ... a running filter takes a new one at once, uncorrelated with the rest ...
  in.speed_scale = 0.99;
  ASSERT_TRUE(f.setCalibration(in));
  EXPECT_EQ(f.odometryScale(), 0.99);
  for (int i = 0; i < Ekf::kDim; ++i)
    if (i != Ekf::kK) {
      EXPECT_EQ(f.cov(Ekf::kK, i), 0.0) << i;
    }
  // ... and a reset keeps it.
  f.reset();
  EXPECT_EQ(f.calibration().speed_scale, 0.99);
  ASSERT_TRUE(f.updatePosition(1, 10, 20, 3));
  EXPECT_EQ(f.odometryScale(), 0.99);
}

TEST(Ekf, RefusesAnImpossibleCalibration) {
  Ekf f;
  const OdometryCalibration good = f.calibration();
  const auto refused = [&](OdometryCalibration c) {
    const bool ok = f.setCalibration(c);
    EXPECT_EQ(f.calibration().speed_scale, good.speed_scale);
    return !ok;
  };
  OdometryCalibration c = good;
  c.speed_scale = 0.3;
  EXPECT_TRUE(refused(c));
  c.speed_scale = 2.5;
  EXPECT_TRUE(refused(c));
  c.speed_scale = NAN;
  EXPECT_TRUE(refused(c));
  c = good;
  c.speed_scale_sigma = -0.01;
  EXPECT_TRUE(refused(c));
  c = good;
  c.yaw_bias_rad_s = 20 * kDeg;
  EXPECT_TRUE(refused(c));
  c = good;
  c.yaw_bias_sigma_rad_s = INFINITY;
  EXPECT_TRUE(refused(c));
  c = good;
  c.speed_scale = 1.5;
  EXPECT_TRUE(f.setCalibration(c)) << "1.5 is a possible scale";
  EXPECT_EQ(f.calibration().speed_scale, 1.5);
}

TEST(Ekf, GatesAnOutlierAndResetsAfterAJump) {
  DriveSpec s;
  s.duration = 60;
  DriveResult r = drive(s);
  Ekf& f = r.ekf;
  const double e0 = f.e(), n0 = f.n();
  // One fix 80 m off: rejected, the state does not move.
  EXPECT_FALSE(f.updatePosition(f.time(), e0 + 80, n0, 3));
  EXPECT_EQ(f.e(), e0);
  EXPECT_EQ(f.rejectedFixes(), 1u);
  // Fixes that keep agreeing with each other 200 m away: after the configured
  // run of rejections the filter believes them.
  const uint32_t runs = ekfDefaults(EkfDesc{}).reset_after_rejects;
  for (uint32_t i = 0; i < runs; ++i) f.updatePosition(f.time(), e0 + 200, n0, 3);
  EXPECT_EQ(f.resets(), 1u);
  EXPECT_NEAR(f.e(), e0 + 200, 1e-6);
}

// Before any heading, a fix far faster away than a vehicle moves (a receiver
// jump, a fix off the map) is no motion: no heading from it, no speed; it is
// gated like any outlier, and believed after the run of rejections.
TEST(Ekf, AJumpBeforeAnyHeadingGivesNoHeadingAndNoSpeed) {
  Ekf f(EkfDesc{});
  for (int k = 0; k < 3; ++k) f.updatePosition(100.0 + k, 0, 0, 3);
  ASSERT_FALSE(f.headingValid());
  EXPECT_FALSE(f.updatePosition(103.0, 0, 700e3, 3));  // 700 km north in a second
  EXPECT_FALSE(f.headingValid());
  const uint32_t runs = ekfDefaults(EkfDesc{}).reset_after_rejects;
  for (uint32_t i = 1; i < runs; ++i) f.updatePosition(103.0 + i, 0, 700e3, 3);
  EXPECT_EQ(f.resets(), 1u);
  EXPECT_NEAR(f.n(), 700e3, 1e-6);
  EXPECT_FALSE(f.headingValid());
  EXPECT_LT(std::fabs(f.speed()), 1.0);
  // Moving on from there at a vehicle's pace gives a heading again.
  for (int k = 1; k <= 5; ++k) f.updatePosition(103.0 + runs + k, 10.0 * k, 700e3, 3);
  EXPECT_TRUE(f.headingValid());
  EXPECT_NEAR(f.heading(), 90 * kDeg, 10 * kDeg);
}

TEST(Ekf, WeighsFixesByTheirAccuracy) {
  DriveSpec s;
  s.duration = 30;
  const DriveResult base = drive(s);
  Ekf a = base.ekf, b = base.ekf;
  const double e0 = base.ekf.e();
  a.updatePosition(a.time(), e0 + 3, base.ekf.n(), 1.0);   // a precise fix
  b.updatePosition(b.time(), e0 + 3, base.ekf.n(), 10.0);  // a vague one
  EXPECT_GT(a.e() - e0, 2 * (b.e() - e0));
  EXPECT_GT(b.e() - e0, 0.0);
}

TEST(Ekf, EstimatesTheSigmaOfFixesWithoutAccuracy) {
  DriveSpec s;
  s.report_sigma = false;
  s.gnss_sigma = 1.5;
  s.duration = 200;
  const DriveResult r = drive(s);
  // Starts at the default (5 m) and learns the fixes' real noise from the innovations.
  EXPECT_NEAR(r.ekf.adaptiveSigma(), 1.5, 0.6);
  EXPECT_LT(median(window(r, r.err, 100, 201)), 1.2);
}

TEST(Ekf, HeadingFromDisplacementWithoutCourse) {
  DriveSpec s;
  s.gnss_speed = false;  // no GNSS course or speed: heading from the first fixes' displacement
  s.duration = 60;
  const DriveResult r = drive(s);
  ASSERT_TRUE(r.ekf.headingValid());
  EXPECT_NEAR(r.ekf.heading(), 30 * kDeg, 3 * kDeg);
  EXPECT_LT(median(window(r, r.err, 30, 61)), 0.6 * 1.18 * s.gnss_sigma);
}

TEST(Ekf, ExtrapolateDoesNotChangeTheFilter) {
  DriveSpec s;
  s.duration = 20;
  const DriveResult r = drive(s);
  double x[Ekf::kDim], sigma = 0;
  const double e = r.ekf.e(), t = r.ekf.time();
  r.ekf.extrapolate(t + 0.5, x, &sigma);
  EXPECT_EQ(r.ekf.e(), e);
  EXPECT_EQ(r.ekf.time(), t);
  EXPECT_NEAR(std::hypot(x[Ekf::kE] - e, x[Ekf::kN] - r.ekf.n()), 0.5 * 12, 0.3);
  EXPECT_GE(sigma, r.ekf.positionSigma());
}

TEST(Ekf, WrapsAngles) {
  EXPECT_NEAR(wrapPi(3 * kPi / 2), -kPi / 2, 1e-12);
  EXPECT_NEAR(wrapPi(-3 * kPi / 2), kPi / 2, 1e-12);
  EXPECT_NEAR(wrapTwoPi(-0.25), 2 * kPi - 0.25, 1e-12);
  EXPECT_NEAR(wrapTwoPi(7 * kPi), kPi, 1e-12);
}

}  // namespace
}  // namespace blvd::track
