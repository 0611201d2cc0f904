#include "track/ekf.h"
#include "core/math.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace blvd::track {
namespace {
using core::kPi;
constexpr double kDeg = kPi / 180.0;
constexpr double kMaxSubstep = 0.1;       // seconds per integration step

// The integration step's end from `now` towards `t`: `t` within a step, and
// `t` too where a step no longer moves a clock this large (past 2^49 s a
// double's spacing exceeds the step, and now + dt == now would loop for ever).
double stepEnd(double now, double t) {
  const double next = now + kMaxSubstep;
  return t - now <= kMaxSubstep || !(next > now) ? t : next;
}
constexpr double kAnchorMinDist = 10.0;   // metres between fixes for a heading from displacement
// Faster than any road vehicle (about 400 km/h): such a displacement is a jump
// of the fixes (an outlier, a receiver reset, a pose off the map), not motion,
// and goes through the outlier gate instead of giving a heading and a speed.
constexpr double kMaxDisplacementSpeed = 110.0;
constexpr uint32_t kScalarResetAfter = 25;  // consecutive gated speed/heading updates that force the value

double orDefault(double v, double d) { return v > 0 ? v : d; }

void symmetrize(double P[Ekf::kDim][Ekf::kDim]) {
  for (int i = 0; i < Ekf::kDim; ++i)
    for (int j = i + 1; j < Ekf::kDim; ++j) P[i][j] = P[j][i] = 0.5 * (P[i][j] + P[j][i]);
}
}  // namespace

double wrapPi(double a) {
  a = std::fmod(a + kPi, 2 * kPi);
  if (a <= 0) a += 2 * kPi;
  return a - kPi;
}

double wrapTwoPi(double a) {
  a = std::fmod(a, 2 * kPi);
  if (a < 0) a += 2 * kPi;
  return a >= 2 * kPi ? 0 : a;
}

EkfDesc ekfDefaults(const EkfDesc& in) {
  EkfDesc d = in;
  d.uere_m = orDefault(d.uere_m, 4.0);
  d.default_sigma_m = orDefault(d.default_sigma_m, 5.0);
  d.min_sigma_m = orDefault(d.min_sigma_m, 0.5);
  d.adapt_rate = orDefault(d.adapt_rate, 0.05);
  d.gate_chi2_2dof = orDefault(d.gate_chi2_2dof, 13.82);
  d.gate_chi2_1dof = orDefault(d.gate_chi2_1dof, 10.83);
  if (d.reset_after_rejects == 0) d.reset_after_rejects = 5;
  d.q_pos = orDefault(d.q_pos, 0.002);
  d.q_speed = orDefault(d.q_speed, 4.0);
  d.q_heading = orDefault(d.q_heading, (0.2 * kDeg) * (0.2 * kDeg));
  d.q_bias = orDefault(d.q_bias, (0.01 * kDeg) * (0.01 * kDeg));
  d.q_turn = orDefault(d.q_turn, (20 * kDeg) * (20 * kDeg));
  d.odo_speed_sigma = orDefault(d.odo_speed_sigma, 0.1);
  d.gnss_speed_sigma = orDefault(d.gnss_speed_sigma, 0.3);
  d.heading_sigma_deg = orDefault(d.heading_sigma_deg, 2.0);
  d.track_min_speed = orDefault(d.track_min_speed, 3.0);
  d.init_bias_sigma_dps = orDefault(d.init_bias_sigma_dps, 1.0);
  d.init_scale_sigma = orDefault(d.init_scale_sigma, 0.05);
  d.q_scale = orDefault(d.q_scale, 1e-8);
  d.gyro_timeout_s = orDefault(d.gyro_timeout_s, 0.5);
  d.track_width_m = orDefault(d.track_width_m, 1.6);
  return d;
}

Ekf::Ekf(const EkfDesc& desc) : d_(ekfDefaults(desc)) {
  prior_.speed_scale_sigma = d_.init_scale_sigma;
  prior_.yaw_bias_sigma_rad_s = d_.init_bias_sigma_dps * kDeg;
  reset();
}

OdometryCalibration Ekf::calibration() const {
  if (!initialized_) return prior_;
  OdometryCalibration c;
  c.speed_scale = x_[kK];
  c.speed_scale_sigma = std::sqrt(std::max(0.0, P_[kK][kK]));
  c.yaw_bias_rad_s = x_[kB];
  c.yaw_bias_sigma_rad_s = std::sqrt(std::max(0.0, P_[kB][kB]));
  return c;
}

bool Ekf::setCalibration(const OdometryCalibration& c) {
  const bool finite = std::isfinite(c.speed_scale) && std::isfinite(c.speed_scale_sigma) &&
                      std::isfinite(c.yaw_bias_rad_s) && std::isfinite(c.yaw_bias_sigma_rad_s);
  if (!finite || c.speed_scale < 0.5 || c.speed_scale > 2 || std::fabs(c.yaw_bias_rad_s) > 10 * kDeg ||
      c.speed_scale_sigma < 0 || c.yaw_bias_sigma_rad_s < 0)
    return false;
  prior_ = c;
  prior_.speed_scale_sigma = std::max(c.speed_scale_sigma, kMinScaleSigma);
  prior_.yaw_bias_sigma_rad_s = std::max(c.yaw_bias_sigma_rad_s, kMinYawBiasSigmaRadS);
  if (initialized_) applyCalibration();
  return true;
}

void Ekf::applyCalibration() {
  for (int i = 0; i < kDim; ++i) P_[kK][i] = P_[i][kK] = P_[kB][i] = P_[i][kB] = 0;
  x_[kK] = prior_.speed_scale;
  x_[kB] = prior_.yaw_bias_rad_s;
  P_[kK][kK] = prior_.speed_scale_sigma * prior_.speed_scale_sigma;
  P_[kB][kB] = prior_.yaw_bias_sigma_rad_s * prior_.yaw_bias_sigma_rad_s;
}

void Ekf::reset() {
  std::memset(x_, 0, sizeof x_);
  std::memset(P_, 0, sizeof P_);
  t_ = 0;
  initialized_ = heading_valid_ = false;
  omega_ = 0;
  gyro_t_ = -1e300;
  odometer_ = 0;
  r_hat_ = d_.default_sigma_m * d_.default_sigma_m;
  consecutive_rejects_ = rejected_total_ = resets_ = 0;
  std::memset(scalar_rejects_, 0, sizeof scalar_rejects_);
}

void Ekf::propagate(double x[kDim], double P[kDim][kDim], double dt, double now) const {
  if (dt <= 0) return;
  const bool gyro = now - gyro_t_ <= d_.gyro_timeout_s;
  const double omega = gyro ? omega_ : 0.0;
  const double v = x[kV];
  if (!heading_valid_) {
    // Direction unknown: the position stays, its uncertainty grows by the distance driven.
    const double grow = v * v * dt * dt + d_.q_pos * dt;
    P[kE][kE] += grow;
    P[kN][kN] += grow;
    P[kV][kV] += d_.q_speed * dt;
    P[kB][kB] += (gyro ? d_.q_bias : d_.q_turn) * dt;
    P[kK][kK] += d_.q_scale * dt;
    return;
  }
  const double psidot = -(omega - x[kB]);
  const double psim = x[kPsi] + 0.5 * psidot * dt;
  const double s = std::sin(psim), c = std::cos(psim);
  x[kE] += v * dt * s;
  x[kN] += v * dt * c;
  x[kPsi] = wrapTwoPi(x[kPsi] + psidot * dt);

  // F = I + the partial derivatives below (psim depends on psi and, through psidot, on b).
  double F[kDim][kDim] = {};
  for (int i = 0; i < kDim; ++i) F[i][i] = 1;
  F[kE][kPsi] = v * dt * c;
  F[kE][kV] = dt * s;
  F[kE][kB] = 0.5 * dt * v * dt * c;
  F[kN][kPsi] = -v * dt * s;
  F[kN][kV] = dt * c;
  F[kN][kB] = -0.5 * dt * v * dt * s;
  F[kPsi][kB] = dt;
  double FP[kDim][kDim];
  for (int i = 0; i < kDim; ++i)
    for (int j = 0; j < kDim; ++j) {
      double acc = 0;
      for (int k = 0; k < kDim; ++k) acc += F[i][k] * P[k][j];
      FP[i][j] = acc;
    }
  for (int i = 0; i < kDim; ++i)
    for (int j = 0; j < kDim; ++j) {
      double acc = 0;
      for (int k = 0; k < kDim; ++k) acc += FP[i][k] * F[j][k];
      P[i][j] = acc;
    }
  P[kE][kE] += d_.q_pos * dt;
  P[kN][kN] += d_.q_pos * dt;
  P[kPsi][kPsi] += d_.q_heading * dt;
  P[kV][kV] += d_.q_speed * dt;
  P[kB][kB] += (gyro ? d_.q_bias : d_.q_turn) * dt;
  P[kK][kK] += d_.q_scale * dt;
  symmetrize(P);
}

void Ekf::predict(double t) {
  if (!initialized_) {
    t_ = std::max(t_, t);
    return;
  }
  while (t > t_) {
    const double dt = std::min(kMaxSubstep, t - t_);
    propagate(x_, P_, dt, t_);
    odometer_ += std::fabs(x_[kV]) * dt;
    t_ = stepEnd(t_, t);
  }
}

void Ekf::extrapolate(double t, double out[kDim], double* sigma_out) const {
  double P[kDim][kDim];
  std::memcpy(out, x_, sizeof x_);
  std::memcpy(P, P_, sizeof P_);
  double now = t_;
  if (initialized_)
    while (t > now) {
      const double dt = std::min(kMaxSubstep, t - now);
      propagate(out, P, dt, now);
      now = stepEnd(now, t);
    }
  if (sigma_out) {
    const double a = P[kE][kE], b = P[kN][kN], c = P[kE][kN];
    const double tr = 0.5 * (a + b), det = std::sqrt(std::max(0.0, 0.25 * (a - b) * (a - b) + c * c));
    *sigma_out = std::sqrt(std::max(0.0, tr + det));
  }
}

double Ekf::positionSigma() const {
  const double a = P_[kE][kE], b = P_[kN][kN], c = P_[kE][kN];
  const double tr = 0.5 * (a + b), det = std::sqrt(std::max(0.0, 0.25 * (a - b) * (a - b) + c * c));
  return std::sqrt(std::max(0.0, tr + det));
}

void Ekf::initPosition(double t, double e, double n, double sigma_m) {
  for (int i = 0; i < kDim; ++i) P_[kE][i] = P_[i][kE] = P_[kN][i] = P_[i][kN] = 0;
  x_[kE] = e;
  x_[kN] = n;
  P_[kE][kE] = P_[kN][kN] = sigma_m * sigma_m;
  if (!initialized_) {
    x_[kPsi] = x_[kV] = 0;
    P_[kPsi][kPsi] = kPi * kPi;
    P_[kV][kV] = 100.0;
    applyCalibration();
    t_ = t;
    initialized_ = true;
  }
  anchor_e_ = e;
  anchor_n_ = n;
  anchor_t_ = t;
  anchor_sigma_ = sigma_m;
  consecutive_rejects_ = 0;
}

void Ekf::initPose(double t, double e, double n, double sigma_m, double psi, double psi_sigma) {
  reset();
  initPosition(t, e, n, sigma_m);
  initHeading(psi, psi_sigma);
}

void Ekf::addPositionVariance(double var) {
  if (!(var > 0)) return;
  P_[kE][kE] += var;
  P_[kN][kN] += var;
}

void Ekf::initHeading(double psi, double sigma) {
  for (int i = 0; i < kDim; ++i) P_[kPsi][i] = P_[i][kPsi] = 0;
  x_[kPsi] = wrapTwoPi(psi);
  P_[kPsi][kPsi] = sigma * sigma;
  heading_valid_ = true;
  scalar_rejects_[kPsi] = 0;
}

bool Ekf::updatePosition(double t_fix, double ze, double zn, double sigma_in) {
  const bool adaptive = !(sigma_in > 0);
  const double sigma_m = std::max(adaptive ? std::sqrt(r_hat_) : sigma_in, d_.min_sigma_m);
  if (!initialized_) {
    initPosition(t_fix, ze, zn, sigma_m);
    return true;
  }
  if (!heading_valid_) {
    // A heading from displacement once the vehicle has clearly moved (the
    // direction's sigma is the position sigma over the distance).
    const double de = ze - anchor_e_, dn = zn - anchor_n_;
    const double dist = std::hypot(de, dn);
    const double noise = std::hypot(sigma_m, anchor_sigma_);
    const double dt = t_fix - anchor_t_;
    const bool jump = !(dist - 3 * noise <= kMaxDisplacementSpeed * std::max(dt, 0.0));
    if (dist > std::max(kAnchorMinDist, 3 * noise) && !jump) {
      initHeading(std::atan2(de, dn), std::max(5 * kDeg, std::atan2(2 * noise, dist)));
      if (dt > 0 && P_[kV][kV] > 1.0) {
        x_[kV] = dist / dt;
        P_[kV][kV] = (noise / dt) * (noise / dt) + 1.0;
      }
      initPosition(t_fix, ze, zn, sigma_m);
      return true;
    }
  }
  // A late fix is compared with the state moved back along its velocity.
  const double lag = t_ - t_fix;
  double he = x_[kE], hn = x_[kN];
  if (lag > 0 && heading_valid_) {
    he -= x_[kV] * lag * std::sin(x_[kPsi]);
    hn -= x_[kV] * lag * std::cos(x_[kPsi]);
  }
  const double ye = ze - he, yn = zn - hn;
  const double r = sigma_m * sigma_m;
  const double s00 = P_[kE][kE] + r, s11 = P_[kN][kN] + r, s01 = P_[kE][kN];
  const double det = s00 * s11 - s01 * s01;
  if (!(det > 0)) return false;
  const double i00 = s11 / det, i11 = s00 / det, i01 = -s01 / det;
  const double d2 = ye * (i00 * ye + i01 * yn) + yn * (i01 * ye + i11 * yn);
  if (d2 > d_.gate_chi2_2dof) {
    ++rejected_total_;
    if (++consecutive_rejects_ >= d_.reset_after_rejects) {
      // The fixes agree with each other, not with us: believe them.
      ++resets_;
      initPosition(t_fix, ze, zn, sigma_m);
    }
    return false;
  }
  consecutive_rejects_ = 0;
  if (adaptive) {
    // One sample of the fix variance per axis: innovation power minus the prior's share.
    const double sample = 0.5 * (ye * ye + yn * yn) - 0.5 * (P_[kE][kE] + P_[kN][kN]);
    const double lo = d_.min_sigma_m * d_.min_sigma_m, hi = d_.default_sigma_m * d_.default_sigma_m;
    r_hat_ = std::clamp((1 - d_.adapt_rate) * r_hat_ + d_.adapt_rate * sample, lo, hi);
  }
  // K = P H^T S^-1 with H = [I2 0].
  double K[kDim][2];
  for (int i = 0; i < kDim; ++i) {
    K[i][0] = P_[i][kE] * i00 + P_[i][kN] * i01;
    K[i][1] = P_[i][kE] * i01 + P_[i][kN] * i11;
  }
  for (int i = 0; i < kDim; ++i) x_[i] += K[i][0] * ye + K[i][1] * yn;
  x_[kPsi] = wrapTwoPi(x_[kPsi]);
  // Joseph form: P = (I - KH) P (I - KH)^T + K R K^T.
  double A[kDim][kDim];
  for (int i = 0; i < kDim; ++i)
    for (int j = 0; j < kDim; ++j) A[i][j] = (i == j ? 1.0 : 0.0) - (j == kE ? K[i][0] : j == kN ? K[i][1] : 0.0);
  double AP[kDim][kDim];
  for (int i = 0; i < kDim; ++i)
    for (int j = 0; j < kDim; ++j) {
      double acc = 0;
      for (int k = 0; k < kDim; ++k) acc += A[i][k] * P_[k][j];
      AP[i][j] = acc;
    }
  for (int i = 0; i < kDim; ++i)
    for (int j = 0; j < kDim; ++j) {
      double acc = 0;
      for (int k = 0; k < kDim; ++k) acc += AP[i][k] * A[j][k];
      P_[i][j] = acc + r * (K[i][0] * K[j][0] + K[i][1] * K[j][1]);
    }
  symmetrize(P_);
  return true;
}

bool Ekf::scalarUpdate(const double H[kDim], int idx, double residual, double r, double gate) {
  double PH[kDim];  // P H^T
  for (int i = 0; i < kDim; ++i) {
    double acc = 0;
    for (int k = 0; k < kDim; ++k) acc += P_[i][k] * H[k];
    PH[i] = acc;
  }
  double S = r;
  for (int i = 0; i < kDim; ++i) S += H[i] * PH[i];
  if (!(S > 0)) return false;
  if (residual * residual / S > gate) {
    if (idx < 0 || ++scalar_rejects_[idx] < kScalarResetAfter || !(H[idx] != 0)) return false;
    // Persistently disagreeing: our value is the wrong one.
    for (int i = 0; i < kDim; ++i) P_[idx][i] = P_[i][idx] = 0;
    x_[idx] += residual / H[idx];
    P_[idx][idx] = r / (H[idx] * H[idx]);
    scalar_rejects_[idx] = 0;
    return true;
  }
  if (idx >= 0) scalar_rejects_[idx] = 0;
  double K[kDim];
  for (int i = 0; i < kDim; ++i) K[i] = PH[i] / S;
  for (int i = 0; i < kDim; ++i) x_[i] += K[i] * residual;
  // Joseph form: (I - K H) P (I - K H)^T + K r K^T = P - K PH^T - PH K^T + K S K^T.
  for (int i = 0; i < kDim; ++i)
    for (int j = 0; j < kDim; ++j) P_[i][j] += -K[i] * PH[j] - PH[i] * K[j] + K[i] * K[j] * S;
  symmetrize(P_);
  return true;
}

bool Ekf::updateSpeed(double v, double sigma) {
  if (!initialized_) return false;
  double H[kDim] = {};
  H[kV] = 1;
  return scalarUpdate(H, kV, v - x_[kV], sigma * sigma, d_.gate_chi2_1dof);
}

bool Ekf::updateOdometrySpeed(double v, double sigma) {
  if (!initialized_) return false;
  double H[kDim] = {};
  H[kV] = x_[kK];
  H[kK] = x_[kV];
  return scalarUpdate(H, kV, v - x_[kK] * x_[kV], sigma * sigma, d_.gate_chi2_1dof);
}

bool Ekf::updateLine(double qe, double qn, double ne, double nn, double offset, double sigma) {
  if (!initialized_) return false;
  double H[kDim] = {};
  H[kE] = ne;
  H[kN] = nn;
  const double predicted = ne * (x_[kE] - qe) + nn * (x_[kN] - qn);
  return scalarUpdate(H, -1, offset - predicted, sigma * sigma, d_.gate_chi2_1dof);
}

bool Ekf::updateHeading(double psi, double sigma) {
  if (!initialized_) return false;
  if (!heading_valid_) {
    initHeading(psi, sigma);
    return true;
  }
  double H[kDim] = {};
  H[kPsi] = 1;
  const bool ok = scalarUpdate(H, kPsi, wrapPi(psi - x_[kPsi]), sigma * sigma, d_.gate_chi2_1dof);
  x_[kPsi] = wrapTwoPi(x_[kPsi]);
  return ok;
}

void Ekf::setYawRate(double t, double omega) {
  omega_ = omega;
  gyro_t_ = t;
}

}  // namespace blvd::track
