// Fusion of GNSS and vehicle odometry: an extended Kalman filter over
// x = [east, north, heading, speed, yaw-rate bias, odometry speed scale] in the
// local frame.
//
// Motion model (Thrun, Burgard & Fox, "Probabilistic Robotics" §3.3 and §5.3;
// the unicycle used by most automotive dead reckoning):
//   d(east)/dt  = v sin(psi),  d(north)/dt = v cos(psi)      psi clockwise from north
//   d(psi)/dt   = -(omega - b)                               omega: measured yaw rate, positive left
//   dv/dt = 0 + noise,  db/dt = 0 + noise,  dk/dt = 0 + noise
// integrated with the heading at the middle of the step. Odometry measures
// k * v: wheel speeds read a little off the ground speed (tyre radius, wear,
// pressure; 0.9 % low on the comma2k19 RAV4), and an uncalibrated scale makes
// the filter trail the fixes by the speed error times its time constant. GNSS
// speed and position calibrate k (the classic odometer scale state, Groves,
// "Principles of GNSS, Inertial, and Multisensor Integrated Navigation Systems",
// 2nd ed., §16.2.1), so dead reckoning through an outage uses calibrated speed. With no yaw-rate
// sensor, omega = 0 and b becomes the turn rate itself (a constant-turn-rate
// model), with more process noise.
//
// Measurements: GNSS position (weighted by the fix's reported accuracy: GST
// sigma, else HDOP x UERE, else a default), GNSS speed and course, odometry
// speed (CAN speed or the mean wheel speed) and an absolute heading when one is
// given. Every update passes a chi-square gate on its normalised innovation
// (Bar-Shalom, Li & Kirubarajan 2001, §5.4.2: validation gate) so an outlier fix
// is rejected; a run of rejected fixes (the filter, not the fixes, is wrong)
// resets the position. Outages are prediction only: the covariance grows.
//
// Contract: plain value type, no allocation, no threads, deterministic.
#pragma once
#include <cmath>
#include <cstdint>

#include "core/math.h"

namespace blvd::track {

// Zero means "default" for every field (see ekfDefaults()).
struct EkfDesc {
  double uere_m = 0;               // user equivalent range error: per-axis sigma = HDOP x UERE / sqrt(2); default 4 m
  double default_sigma_m = 0;      // per-axis sigma of a fix with neither GST nor HDOP, before the
                                   // innovations have estimated it (see updatePosition); default 5 m
  double adapt_rate = 0;           // weight of one fix in that estimate; default 0.05
  double min_sigma_m = 0;          // floor of a fix's per-axis sigma (receivers claim too much); default 0.5 m
  double gate_chi2_2dof = 0;       // position gate; default 13.82 (99.9 %)
  double gate_chi2_1dof = 0;       // speed / heading gate; default 10.83 (99.9 %)
  uint32_t reset_after_rejects = 0;  // consecutive rejected fixes that reset the position; default 5
  double q_pos = 0;                // position process noise (slip, model error), m^2/s; default 0.002
  double q_speed = 0;              // speed random walk, (m/s)^2/s; default 4 (2 m/s^2)
  double q_heading = 0;            // heading noise with a gyro, rad^2/s; default (0.2 deg)^2/s: a yaw-rate
                                   // sensor's angle random walk (0.3 deg/s of noise at 50 Hz is 0.04 deg/sqrt(s))
                                   // with room for its scale and alignment errors (was (0.5 deg)^2/s: 3-4 % more
                                   // on-cell misses over 200 drives, README)
  double q_bias = 0;               // yaw-rate bias random walk, (rad/s)^2/s; default (0.01 deg/s)^2/s
  double q_turn = 0;               // turn-rate random walk without a gyro, (rad/s)^2/s; default (20 deg/s)^2/s
  double odo_speed_sigma = 0;      // odometry speed, m/s; default 0.1
  double gnss_speed_sigma = 0;     // GNSS speed over ground, m/s; default 0.3
  double heading_sigma_deg = 0;    // an absolute heading (kOdoHeading); default 2
  double track_min_speed = 0;      // GNSS course is used above this speed, m/s; default 3
  double init_bias_sigma_dps = 0;  // initial yaw-rate bias sigma, deg/s; default 1
  double init_scale_sigma = 0;     // initial odometry scale sigma; default 0.05
  double q_scale = 0;              // odometry scale random walk, 1/s; default 1e-8
  double gyro_timeout_s = 0;       // a yaw rate older than this is not used; default 0.5
  double track_width_m = 0;        // rear track for a yaw rate from wheel speeds; default 1.6
};

EkfDesc ekfDefaults(const EkfDesc& desc);

// The odometry's calibration: the wheel-speed scale and the yaw-rate bias. They
// belong to the vehicle, not to the drive, so a host keeps them between drives
// (automotive dead reckoning stores its odometer scale factor and gyro bias in
// non-volatile memory at key-off; Groves, 2nd ed., §16.2.1 and §16.3.4) and
// gives them back at the next start instead of learning them again from GNSS.
struct OdometryCalibration {
  double speed_scale = 1;          // odometry reads speed_scale x ground speed
  double speed_scale_sigma = 0;    // its 1-sigma
  double yaw_bias_rad_s = 0;       // measured yaw rate minus the true one, positive left
  double yaw_bias_sigma_rad_s = 0; // its 1-sigma
};

// The smallest sigmas Ekf::setCalibration accepts: between two drives the
// tyres' pressure and temperature move the scale by a few tenths of a percent,
// and a MEMS gyro's bias changes from one power-up to the next (its turn-on
// bias repeatability, of the order of 0.01-0.1 deg/s for automotive yaw-rate sensors).
constexpr double kMinScaleSigma = 0.002;
constexpr double kMinYawBiasSigmaRadS = 0.05 * core::kDegToRad;

class Ekf {
 public:
  enum : int { kE = 0, kN = 1, kPsi = 2, kV = 3, kB = 4, kK = 5, kDim = 6 };

  explicit Ekf(const EkfDesc& desc = EkfDesc{});

  void reset();

  // Advances the state to time t (no-op for t <= time()).
  void predict(double t);

  // A GNSS position (local frame, metres) with its per-axis sigma, valid at t_fix.
  // A fix older than time() is applied to the state moved back along the current
  // velocity (a late fix). Returns false when gated out.
  // sigma_m <= 0 means the receiver did not say: the sigma is then estimated from
  // the innovations, R = E[y y^T] - H P H^T (innovation-based adaptive
  // estimation, Mehra 1970; Mohamed & Schwarz 1999, J. Geodesy 73 §3), as an
  // exponential average starting at default_sigma_m and kept within
  // [min_sigma_m, default_sigma_m].
  bool updatePosition(double t_fix, double e, double n, double sigma_m);
  // Ground speed over ground (GNSS), m/s.
  bool updateSpeed(double v, double sigma);
  // Speed from the vehicle's odometry (measures k * v), m/s.
  bool updateOdometrySpeed(double v, double sigma);
  // The position lies `offset` metres along the unit normal (ne, nn) from the
  // line through (qe, qn): a map constraint ("the vehicle is on this street"),
  // one dimension only, so it says nothing about the position along the street.
  bool updateLine(double qe, double qn, double ne, double nn, double offset, double sigma);
  // Absolute heading (GNSS course or a heading sensor), clockwise from north, radians.
  bool updateHeading(double psi, double sigma);
  // The yaw rate used by the following predictions, rad/s positive left; t its time.
  void setYawRate(double t, double omega);
  // Drops the yaw-rate input (no gyro: constant-turn-rate model).
  void clearYawRate() { gyro_t_ = -1e300; }
  // Adds variance to the position (east and north), e.g. when a constraint applied
  // earlier turns out to be wrong.
  void addPositionVariance(double var);
  // Sets the heading (first course from GNSS, or from displacement).
  void initHeading(double psi, double sigma);
  // Starts the filter afresh at a known pose (a stored start pose): position
  // (per-axis sigma) and heading (sigma) at time t, speed unknown, scale and
  // bias from the calibration prior.
  void initPose(double t, double e, double n, double sigma_m, double psi, double psi_sigma);

  // The filter's estimate of the odometry's calibration (the prior it started
  // from while not initialised).
  OdometryCalibration calibration() const;
  // Starts from `c` instead of the defaults (scale 1 +- init_scale_sigma, bias
  // 0 +- init_bias_sigma_dps), now and after every reset: a running filter takes
  // the values and variances (sigmas raised to kMinScaleSigma /
  // kMinYawBiasSigmaRadS) and forgets their correlation with the other states.
  // False, changing nothing, for a scale outside [0.5, 2], a bias beyond 10 deg/s,
  // a negative sigma or a non-finite field.
  bool setCalibration(const OdometryCalibration& c);

  bool initialized() const { return initialized_; }
  bool headingValid() const { return heading_valid_; }
  double time() const { return t_; }
  const double* state() const { return x_; }
  double cov(int i, int j) const { return P_[i][j]; }
  double e() const { return x_[kE]; }
  double n() const { return x_[kN]; }
  double heading() const { return x_[kPsi]; }  // radians, [0, 2 pi)
  double speed() const { return x_[kV]; }
  double bias() const { return x_[kB]; }
  // The heading's rate of change, rad/s clockwise (the yaw rate less its bias),
  // 0 without a fresh yaw rate.
  double turnRate() const { return t_ - gyro_t_ <= d_.gyro_timeout_s ? -(omega_ - x_[kB]) : 0.0; }
  double odometryScale() const { return x_[kK]; }
  // 1-sigma of the position along its worst axis.
  double positionSigma() const;
  // Distance travelled (integral of |v| dt) since reset.
  double odometer() const { return odometer_; }

  // The state moved ahead to t without changing the filter (for the pose between
  // measurements). out: the state; sigma_out: position sigma.
  void extrapolate(double t, double out[kDim], double* sigma_out) const;

  uint32_t rejectedFixes() const { return rejected_total_; }
  // The estimated per-axis sigma of fixes that carry no accuracy.
  double adaptiveSigma() const { return std::sqrt(r_hat_); }
  uint32_t resets() const { return resets_; }

 private:
  // One prediction step of dt seconds on (x, P); `now` picks the yaw-rate input.
  void propagate(double x[kDim], double P[kDim][kDim], double dt, double now) const;
  // Scalar measurement with Jacobian row H; idx names the state forced on a long
  // run of gated updates (-1: never forced).
  bool scalarUpdate(const double H[kDim], int idx, double residual, double r, double gate);
  void initPosition(double t, double e, double n, double sigma_m);
  // The prior's scale and bias into the state, their variances, no correlations.
  void applyCalibration();

  EkfDesc d_;
  OdometryCalibration prior_;  // where a fresh filter starts its scale and bias
  double x_[kDim] = {};
  double P_[kDim][kDim] = {};
  double t_ = 0;
  bool initialized_ = false;
  bool heading_valid_ = false;
  double omega_ = 0;        // last yaw rate, rad/s positive left
  double gyro_t_ = -1e300;  // its time
  double odometer_ = 0;
  uint32_t consecutive_rejects_ = 0;
  double r_hat_ = 25;  // adaptive fix variance, m^2 (reset to default_sigma_m^2)
  uint32_t scalar_rejects_[kDim] = {};  // consecutive gated speed / heading updates
  // First fix, for a heading from displacement when no course is reported.
  double anchor_e_ = 0, anchor_n_ = 0, anchor_t_ = 0, anchor_sigma_ = 0;
  uint32_t rejected_total_ = 0;
  uint32_t resets_ = 0;
};

// Wraps an angle to (-pi, pi].
double wrapPi(double a);
// Wraps an angle to [0, 2 pi).
double wrapTwoPi(double a);

}  // namespace blvd::track
