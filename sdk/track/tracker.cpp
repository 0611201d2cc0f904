#include "track/tracker.h"
#include "core/math.h"

#include <algorithm>
#include <cmath>

#include "track/lane.h"

namespace blvd::track {
namespace {
using core::kPi;
constexpr double kDeg = kPi / 180.0;
constexpr double kSqrtHalf = 0.70710678118654752440;

double orDefault(double v, double d) { return v > 0 ? v : d; }
// Values no vehicle or receiver gives, ignored as the header's contract says
// (a 10^33 m accuracy or speed overflows the filter's covariance).
constexpr double kMaxFixSigmaM = 1e4;     // a fix this vague holds no position
constexpr double kMaxSpeedMps = 1e3;
constexpr double kMaxYawRateDps = 1e3;
constexpr double kMaxAngleDeg = 720;      // headings and courses, before wrapping
bool plausibleAngle(double deg) { return std::fabs(deg) <= kMaxAngleDeg; }
// What a fix epoch has given the filter so far (Tracker::epoch_parts_).
enum EpochPart : uint32_t { kEpochSpeed = 1u << 0, kEpochTrack = 1u << 1 };
bool finite(double v) { return std::isfinite(v); }
}  // namespace

TrackerDesc trackerDefaults(const TrackerDesc& in) {
  TrackerDesc d = in;
  if (d.ring_capacity == 0) d.ring_capacity = 512;
  if (!(d.gnss_latency_s >= 0)) d.gnss_latency_s = 0;
  d.match_interval_s = orDefault(d.match_interval_s, 1.0);
  d.outage_s = orDefault(d.outage_s, 2.5);
  d.max_extrapolate_s = orDefault(d.max_extrapolate_s, 1.0);
  d.eye_height_m = orDefault(d.eye_height_m, 1.5);
  if (!finite(d.camera_pitch_deg)) d.camera_pitch_deg = 0;
  d.map_aid_min_confidence = orDefault(d.map_aid_min_confidence, 0.9);
  if (!(d.map_aid_sigma_m < 0)) d.map_aid_sigma_m = orDefault(d.map_aid_sigma_m, 0.5);
  d.lane_offset_m = orDefault(d.lane_offset_m, 1.75);
  d.ambiguity_sigmas = orDefault(d.ambiguity_sigmas, 2.5);
  d.ekf = ekfDefaults(d.ekf);
  d.matcher = matcherDefaults(d.matcher);
  return d;
}

Tracker::Tracker(const geo::LocalFrame& frame, const graph::StreetGraph* graph, const TrackerDesc& desc)
    : d_(trackerDefaults(desc)), frame_(frame), ekf_(d_.ekf) {
  if (graph && !graph->halfedges.empty()) matcher_ = std::make_unique<MapMatcher>(*graph, d_.matcher);
  if (matcher_) graph_ = &matcher_->graph();
  ring_.resize(d_.ring_capacity);
  batch_.resize(d_.ring_capacity);
}

Tracker::Tracker(const geo::LocalFrame& frame, const graph::GraphSource* graph, const TrackerDesc& desc)
    : d_(trackerDefaults(desc)), frame_(frame), ekf_(d_.ekf) {
  if (graph && graph->cellCount() > 0) matcher_ = std::make_unique<MapMatcher>(*graph, d_.matcher);
  if (matcher_) graph_ = &matcher_->graph();
  ring_.resize(d_.ring_capacity);
  batch_.resize(d_.ring_capacity);
}

Tracker::~Tracker() = default;

size_t Tracker::bytes() const {
  return sizeof(*this) + (ring_.capacity() + batch_.capacity()) * sizeof(Event) + (matcher_ ? matcher_->bytes() : 0);
}

bool Tracker::push(const Event& ev) {
  std::lock_guard<std::mutex> lock(mu_);
  bool ok = true;
  if (ring_count_ == ring_.size()) {
    ring_head_ = (ring_head_ + 1) % ring_.size();
    --ring_count_;
    ++dropped_;
    ok = false;
  }
  Event& slot = ring_[(ring_head_ + ring_count_) % ring_.size()];
  slot = ev;
  slot.seq = seq_++;
  ++ring_count_;
  high_water_ = std::max(high_water_, static_cast<uint32_t>(ring_count_));
  if (ev.is_gnss) ++gnss_fed_;
  else ++odo_fed_;
  return ok;
}

bool Tracker::feedGnss(const GnssFix& fix) {
  Event ev;
  ev.is_gnss = true;
  ev.gnss = fix;
  ev.t = fix.t - d_.gnss_latency_s;
  return push(ev);
}

bool Tracker::feedOdometry(const Odometry& odo) {
  Event ev;
  ev.is_gnss = false;
  ev.odo = odo;
  ev.t = odo.t;
  return push(ev);
}

void Tracker::reset() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    ring_head_ = ring_count_ = 0;
  }
  forgetDrive();
  st_ = TrackerStats{};
}

void Tracker::forgetDrive() {
  ekf_.reset();
  if (matcher_) matcher_->reset();
  pose_ = Pose{};
  cur_ = CellPoint{};
  confidence_ = 0;
  lateral_mean_ = lateral_mean_var_ = 0;
  agreement_fixes_ = 0;
  street_agrees_ = false;
  last_step_t_ = last_fix_t_ = last_fix_event_t_ = last_gyro_t_ = last_odo_speed_t_ = -1e300;
  epoch_parts_ = 0;
  in_outage_ = false;
}

bool Tracker::clockStepped(double t) {
  if (!ekf_.initialized() || (t > ekf_.time() - kClockStepS && t < ekf_.time() + kMaxGapS)) return false;
  ++st_.clock_steps;
  carried_resets_ += ekf_.resets();
  const OdometryCalibration cal = ekf_.calibration();
  // Where the filter is now is where the vehicle was at the last event of the
  // old clock; the new clock's first event comes some unknown time later (at
  // most the gap a GNSS outage is declared after, or it would not be a step).
  StartPose sp;
  sp.t = t;
  double h = 0;
  frame_.reverse(geo::Enu{ekf_.e(), ekf_.n(), 0}, sp.lat, sp.lon, h);
  sp.heading_deg = ekf_.heading() / kDeg;
  sp.heading_sigma_deg = ekf_.headingValid() ? std::sqrt(std::max(0.0, ekf_.cov(Ekf::kPsi, Ekf::kPsi))) / kDeg : 180;
  sp.sigma_m = ekf_.positionSigma() + std::fabs(ekf_.speed()) * d_.outage_s;
  ekf_.setCalibration(cal);
  if (!setStartPose(sp)) forgetDrive();  // no usable pose (it had diverged): the next fix starts afresh
  return true;
}

bool Tracker::setStartPose(const StartPose& sp) {
  if (!finite(sp.t) || !finite(sp.lat) || !finite(sp.lon) || !finite(sp.heading_deg) || !finite(sp.sigma_m) ||
      !finite(sp.heading_sigma_deg) || std::fabs(sp.lat) > 90 || std::fabs(sp.lon) > 180 || sp.sigma_m < 0 ||
      sp.sigma_m > kMaxFixSigmaM || sp.heading_sigma_deg < 0 || sp.heading_sigma_deg > 180 ||
      !plausibleAngle(sp.heading_deg))
    return false;
  forgetDrive();
  const geo::Enu p = frame_.forward(sp.lat, sp.lon, frame_.h0());
  const double sigma = sp.sigma_m > 0 ? std::max(sp.sigma_m, kStartSigmaMinM) : kStartSigmaDefaultM;
  const double hsig =
      (sp.heading_sigma_deg > 0 ? std::max(sp.heading_sigma_deg, kStartHeadingSigmaMinDeg) : kStartHeadingSigmaDefaultDeg) * kDeg;
  ekf_.initPose(sp.t, p.e, p.n, sigma, sp.heading_deg * kDeg, hsig);
  // The first HMM step from the stored pose (no fix): a matched pose before
  // the first fix, and the chain the fixes continue. The heading is the stored
  // one: it tells the street's two directions apart while the car stands.
  matchStep(nullptr, 0, true);
  return true;
}

TrackerStats Tracker::stats() const {
  TrackerStats s = st_;
  {
    std::lock_guard<std::mutex> lock(mu_);
    s.gnss_fed = gnss_fed_;
    s.odometry_fed = odo_fed_;
    s.ring_dropped = dropped_;
    s.ring_high_water = high_water_;
  }
  s.filter_resets = carried_resets_ + ekf_.resets();
  if (matcher_) s.match = matcher_->stats();
  return s;
}

void Tracker::matchStep(const double* fix_en, double fix_sigma, bool heading_at_rest) {
  if (!matcher_ || !ekf_.initialized()) return;
  MatchObservation obs;
  obs.t = ekf_.time();
  obs.e = ekf_.e();
  obs.n = ekf_.n();
  obs.sigma_m = ekf_.positionSigma();
  obs.heading_rad = ekf_.heading();
  obs.heading_sigma_rad =
      ekf_.headingValid() && (heading_at_rest || std::fabs(ekf_.speed()) > 1.0)
          ? std::sqrt(std::max(0.0, ekf_.cov(Ekf::kPsi, Ekf::kPsi)))
          : 0.0;
  if (fix_en && fix_sigma > 0) {
    obs.fix_e = fix_en[0];
    obs.fix_n = fix_en[1];
    obs.fix_sigma_m = fix_sigma;
  }
  const CellPoint before = cur_;
  if (matcher_->step(obs)) {
    cur_ = matcher_->head();
    // The head's emission cannot tell the end of a cell from the start of its
    // successor (both are the junction point, a fraction of the position sigma
    // apart), so the HMM may name the successor while the position still lies
    // before the junction. The pose's cell follows the nearest-point rule of
    // `follow` (and of the truth): a position before the head cell's start that
    // is nearer to the cell it came from stays on that cell.
    if (before.cell != graph::kNone && before.cell != cur_.cell && cur_.arc_m <= 0.01) {
      bool pred = false;
      for (uint32_t s : graph_->successors(before.cell)) pred |= s == cur_.cell;
      if (pred) {
        const CellPoint q = matcher_->project(before.cell, obs.e, obs.n);
        if (q.cell != graph::kNone && q.dist_m < cur_.dist_m) cur_ = q;
      }
    }
    confidence_ = matcher_->confidence();
    const bool aid = d_.map_aid_sigma_m > 0;
    if (aid && confidence_ < d_.map_aid_min_confidence) ++st_.map_aid_low_confidence;
    else if (aid && !street_agrees_) ++st_.map_aid_disagreeing;
    else if (aid && ambiguous()) ++st_.map_aid_ambiguous;
    else if (aid) {
      // Where the vehicle is expected across the street: its lane, shifted to
      // the inside while it turns through a corner (cornerShift). Right of a
      // bearing h is (cos h, -sin h).
      double offset = expectedOffset(cur_.cell), sigma = d_.map_aid_sigma_m;
      cornerShift(offset, sigma);
      if (ekf_.updateLine(cur_.e, cur_.n, std::cos(cur_.heading_rad), -std::sin(cur_.heading_rad), offset, sigma))
        ++st_.map_aids;
      else
        ++st_.map_aids_rejected;
    }
  } else {
    cur_ = CellPoint{};
    confidence_ = 0;
  }
  last_step_t_ = obs.t;
}

void Tracker::cornerShift(double& offset, double& sigma) const {
  // A vehicle turning through a corner leaves its lane line for the inside: a
  // driver follows an arc tangent to the lane (the circular curve of road
  // design between two tangents, e.g. AASHTO "A Policy on Geometric Design",
  // ch. 3, and the curve cutting observed in driving studies, Spacek 2005,
  // "Track behavior in curve areas", J. Transp. Eng. 131(9)). On an arc of
  // curvature kappa whose heading has turned by dpsi since it left the tangent
  // (or has dpsi to go before it meets the next one), the vehicle is
  // (1 - cos dpsi) / kappa inside that tangent. kappa is the filter's turn rate
  // over its speed, dpsi its heading against the matched street's direction.
  // Without this, the aid pins the filter to the lane line through the corner
  // and the part cut off comes out as an along-track error on the next street
  // (its cross-track before the turn is its along-track after). The shift is
  // a model, not a measurement: half of it is added to the sigma.
  constexpr double kMinCurvature = 0.01;  // 1/m: radius < 100 m; straighter is lane keeping
  constexpr double kMaxShift = 3.0;       // m: about a lane and a half
  const double v = ekf_.speed();
  if (!(std::fabs(v) > 1.0)) return;
  const double kappa = ekf_.turnRate() / v;  // clockwise positive: the inside is to the right
  if (std::fabs(kappa) < kMinCurvature) return;
  const double dpsi = wrapPi(ekf_.heading() - cur_.heading_rad);
  if (std::fabs(dpsi) >= 0.5 * kPi) return;
  const double y = std::clamp((1 - std::cos(dpsi)) / kappa, -kMaxShift, kMaxShift);
  offset += y;
  sigma = std::sqrt(sigma * sigma + 0.25 * y * y);
}

bool Tracker::ambiguous() const {
  // Another street running the same way that the fixes cannot yet tell from
  // the matched one: the map aid would only pick one of the two. The test is
  // the agreement check's own statistic (checkStreetAgreement): the mean of the
  // fixes' offsets from the matched street's lane, with its variance. Were the
  // vehicle in the other street's lane, that mean would be `delta` (the two
  // streets' separation plus the difference of their lanes); the streets are
  // told apart once the mean lies more than ambiguity_sigmas of its standard
  // deviation from `delta` (a gate on the averaged fixes, like the validation
  // gate of Bar-Shalom, Li & Kirubarajan 2001, §5.4.2: n fixes of sigma s tell
  // apart streets a few s / sqrt(n) apart).
  // A fixed reach of ambiguity_sigmas single-fix sigmas held the aid off beside
  // every street within 12.5 m at sigma 5 m however many fixes had
  // told them apart (a fifth of all HMM steps on the Monaco drives).
  const graph::GraphSource& g = *graph_;
  const uint32_t head = cur_.cell;
  const graph::HalfEdge he = g.halfedge(head);
  const uint32_t twin = he.twin, head_end = g.endVertex(head);
  const double reach = d_.ambiguity_sigmas * std::sqrt(std::max(0.0, lateral_mean_var_));
  for (uint32_t i = 0; i < matcher_->candidateCount(); ++i) {
    const CellPoint& c = matcher_->candidate(i);
    if (c.cell == head || c.cell == twin) continue;
    if (std::cos(c.heading_rad - cur_.heading_rad) < 0.8) continue;  // not parallel (> 37 deg)
    // Streets meeting the head's ends continue it rather than run beside it.
    const uint32_t origin = g.halfedge(c.cell).origin, end = g.endVertex(c.cell);
    if (origin == he.origin || end == head_end || origin == head_end || end == he.origin) continue;
    // Offsets are measured to the right of each street's own direction; the two
    // run the same way (above), so they subtract.
    const double delta = (cur_.lateral_m - c.lateral_m) + expectedOffset(c.cell) - expectedOffset(head);
    if (std::fabs(lateral_mean_ - delta) < reach) return true;
  }
  return false;
}

double Tracker::expectedOffset(uint32_t cell) const {
  return laneOffset(graph_->halfedge(cell), d_.left_hand_traffic ? -d_.lane_offset_m : d_.lane_offset_m);
}

void Tracker::checkStreetAgreement(double e, double n, double sigma) {
  if (!matcher_ || cur_.cell == graph::kNone || !(d_.map_aid_sigma_m > 0)) return;
  // Each fix's offset from where the vehicle should be on the matched street,
  // averaged (a running mean over the first fixes, then exponential); the
  // exponential mean of white noise of sigma s has sigma s * sqrt(a / (2 - a)).
  constexpr double kAlpha = 0.2;
  constexpr uint32_t kMinFixes = 5;
  const CellPoint q = matcher_->follow(cur_, e, n, ekf_.heading(), 0.0);
  const double r = q.lateral_m - expectedOffset(q.cell);
  ++agreement_fixes_;
  const double w = std::max(kAlpha, 1.0 / agreement_fixes_);
  lateral_mean_ += (r - lateral_mean_) * w;
  // Its variance for independent offsets of variance sigma^2 + aid sigma^2 (the
  // lane wander), r_var: (1 - w)^2 var + w^2 r_var, which is r_var / n for the
  // running mean and r_var a / (2 - a) in the exponential's steady state.
  const double r_var = sigma * sigma + d_.map_aid_sigma_m * d_.map_aid_sigma_m;
  lateral_mean_var_ = (1 - w) * (1 - w) * lateral_mean_var_ + w * w * r_var;
  const double s = std::sqrt(r_var * kAlpha / (2 - kAlpha));
  const bool was = street_agrees_;
  if (agreement_fixes_ < kMinFixes || std::fabs(lateral_mean_) > 3 * s) street_agrees_ = false;
  else if (std::fabs(lateral_mean_) < 2 * s) street_agrees_ = true;
  if (was && !street_agrees_) {
    // The fixes say we are not on this street: stop pinning the filter to it and
    // give back the certainty the constraint had lent.
    ++st_.map_aid_suspensions;
    ekf_.addPositionVariance(sigma * sigma);
  }
}

void Tracker::processGnss(const GnssFix& f, double t) {
  double sigma = 0;  // unknown: the filter estimates it
  if ((f.flags & kGnssHasHAcc) && f.h_acc_m > 0 && finite(f.h_acc_m)) sigma = f.h_acc_m * kSqrtHalf;
  else if ((f.flags & kGnssHasHdop) && f.hdop > 0 && finite(f.hdop)) sigma = f.hdop * d_.ekf.uere_m * kSqrtHalf;
  if (!(f.flags & kGnssHasLatLon) || f.mode == kGnssModeNoFix || !finite(t) || !finite(f.lat) || !finite(f.lon) ||
      std::fabs(f.lat) > 90 || std::fabs(f.lon) > 180 || sigma > kMaxFixSigmaM) {
    ++st_.gnss_ignored;
    return;
  }
  clockStepped(t);
  const bool repeat = std::fabs(t - last_fix_event_t_) < kSameEpochS;
  if (!repeat) epoch_parts_ = 0;
  if (ekf_.initialized() && t < ekf_.time()) ++st_.late_events;
  ekf_.predict(t);
  const geo::Enu p = frame_.forward(f.lat, f.lon, frame_.h0());
  if (repeat) {
    ++st_.gnss_duplicates;  // one measurement, not two: the filter would trust it twice
  } else {
    checkStreetAgreement(p.e, p.n, sigma > 0 ? sigma : ekf_.adaptiveSigma());
    if (ekf_.updatePosition(t, p.e, p.n, sigma)) {
      ++st_.gnss_used;
      last_fix_t_ = t;
    } else {
      ++st_.gnss_rejected;
    }
  }
  const bool has_speed = (f.flags & kGnssHasSpeed) && f.speed_mps >= 0 && f.speed_mps <= kMaxSpeedMps;
  // With odometry, GNSS speed calibrates the odometry scale; without, it drives the speed.
  if (has_speed && !(epoch_parts_ & kEpochSpeed)) {
    ekf_.updateSpeed(f.speed_mps, d_.ekf.gnss_speed_sigma);
    epoch_parts_ |= kEpochSpeed;
  }
  if (has_speed && (f.flags & kGnssHasTrack) && plausibleAngle(f.track_deg) && f.speed_mps >= d_.ekf.track_min_speed &&
      !(epoch_parts_ & kEpochTrack)) {
    // Course sigma from the velocity noise across the track, plus a floor.
    const double sigma_track = std::atan2(d_.ekf.gnss_speed_sigma, f.speed_mps) + 0.5 * kDeg;
    ekf_.updateHeading(f.track_deg * kDeg, sigma_track);
    epoch_parts_ |= kEpochTrack;
  }
  if (repeat) return;
  last_fix_event_t_ = t;
  if (ekf_.time() - last_step_t_ >= 0.5 * d_.match_interval_s) {
    const double en[2] = {p.e, p.n};
    matchStep(en, sigma > 0 ? sigma : ekf_.adaptiveSigma());
  }
}

void Tracker::noteOutage(Pose& p) {
  const double since_fix = ekf_.time() - last_fix_t_;
  const bool outage = since_fix > d_.outage_s;
  if (outage) p.flags |= kPoseDeadReckoning;
  if (outage && last_fix_t_ > -1e299) {  // an outage after a fix, not a start on odometry
    if (!in_outage_) ++st_.outages;
    st_.longest_outage_s = std::max(st_.longest_outage_s, since_fix);
  }
  in_outage_ = outage;
}

void Tracker::processOdometry(const Odometry& o, bool advance) {
  if (!finite(o.t)) {
    ++st_.odometry_ignored;
    return;
  }
  clockStepped(o.t);
  if (ekf_.initialized() && o.t < ekf_.time()) ++st_.late_events;
  if ((o.flags & kOdoYawRate) && std::fabs(o.yaw_rate_dps) <= kMaxYawRateDps) {
    ekf_.setYawRate(o.t, o.yaw_rate_dps * kDeg);
    last_gyro_t_ = o.t;
  } else if ((o.flags & kOdoWheelSpeeds) && o.t - last_gyro_t_ > d_.ekf.gyro_timeout_s &&
             std::fabs(o.wheel_speeds_mps[2]) <= kMaxSpeedMps && std::fabs(o.wheel_speeds_mps[3]) <= kMaxSpeedMps) {
    // No yaw-rate sensor: the rear axle's wheel-speed difference over its
    // track (the rear wheels are not steered).
    double omega = (o.wheel_speeds_mps[3] - o.wheel_speeds_mps[2]) / d_.ekf.track_width_m;
    if ((o.flags & kOdoGear) && o.reverse) omega = -omega;
    ekf_.setYawRate(o.t, omega);
  }
  double v = NAN;
  if ((o.flags & kOdoSpeed) && finite(o.speed_mps)) {
    v = std::fabs(o.speed_mps);
  } else if (o.flags & kOdoWheelSpeeds) {
    const double* w = o.wheel_speeds_mps;
    v = 0.25 * (std::fabs(w[0]) + std::fabs(w[1]) + std::fabs(w[2]) + std::fabs(w[3]));
  }
  if (v <= kMaxSpeedMps) {  // false for NaN too
    if ((o.flags & kOdoGear) && o.reverse) v = -v;
    ekf_.updateOdometrySpeed(v, d_.ekf.odo_speed_sigma);
    last_odo_speed_t_ = o.t;
  }
  if ((o.flags & kOdoHeading) && plausibleAngle(o.heading_deg)) ekf_.updateHeading(o.heading_deg * kDeg, d_.ekf.heading_sigma_deg * kDeg);
  // These samples describe the interval that ends at o.t (see update()), so
  // the filter moves to o.t with them rather than with the previous ones.
  if (advance) ekf_.predict(o.t);
  // Dead reckoning through an outage still moves along the graph.
  const double now = ekf_.time();
  if (ekf_.initialized() && now - last_step_t_ >= d_.match_interval_s && now - last_fix_event_t_ >= 1.5 * d_.match_interval_s)
    matchStep();
}

const Pose& Tracker::update(double t) {
  size_t n = 0;
  {
    std::lock_guard<std::mutex> lock(mu_);
    for (; n < ring_count_; ++n) batch_[n] = ring_[(ring_head_ + n) % ring_.size()];
    ring_head_ = ring_count_ = 0;
  }
  // Time order, ties in feed order (insertion sort: batches are short and nearly sorted).
  for (size_t i = 1; i < n; ++i) {
    for (size_t j = i; j > 0; --j) {
      const Event& a = batch_[j - 1];
      const Event& b = batch_[j];
      if (a.t < b.t || (a.t == b.t && a.seq < b.seq) || !(b.t == b.t)) break;
      std::swap(batch_[j - 1], batch_[j]);
    }
  }
  for (size_t i = 0; i < n; ++i) {
    const Event& ev = batch_[i];
    if (ev.is_gnss) {
      processGnss(ev.gnss, ev.t);
    } else {
      // A wheel speed (counted over the last sample period) or a yaw rate
      // describes the interval that ends at its stamp (Groves 2013, §16.2:
      // odometry as distance increments); one sample comes as several CAN
      // frames of the same stamp, so the filter moves to that time once all of
      // them are in.
      const bool last = !(i + 1 < n && !batch_[i + 1].is_gnss && batch_[i + 1].t == ev.t);
      processOdometry(ev.odo, last);
    }
  }

  Pose& p = pose_;
  p = Pose{};
  p.t = t;
  if (!ekf_.initialized()) return p;
  double x[Ekf::kDim], sigma = 0;
  const double te = finite(t) ? std::min(t, ekf_.time() + d_.max_extrapolate_s) : ekf_.time();
  ekf_.extrapolate(te, x, &sigma);
  p.e = x[Ekf::kE];
  p.n = x[Ekf::kN];
  p.heading_deg = x[Ekf::kPsi] / kDeg;
  p.speed_mps = x[Ekf::kV];
  p.pos_sigma_m = sigma;
  p.flags = kPoseValid | (ekf_.headingValid() ? static_cast<uint32_t>(kPoseHeadingValid) : 0u);
  const double psi_sigma = ekf_.headingValid() ? std::sqrt(std::max(0.0, ekf_.cov(Ekf::kPsi, Ekf::kPsi))) : 0.0;
  p.heading_sigma_deg = psi_sigma / kDeg;
  noteOutage(p);

  // Off the map (graph::onMap), the nearest street may be hundreds of
  // kilometres away: no match, and matching starts afresh on the way back.
  if (graph_ && !graph::onMap(*graph_, p.e, p.n)) {
    p.flags |= kPoseOffMap;
    cur_ = CellPoint{};
  }
  // follow() picks successors by heading only while moving.
  const double hsig = std::fabs(x[Ekf::kV]) > 1.0 ? psi_sigma : 0.0;
  if (matcher_ && cur_.cell != graph::kNone) {
    cur_ = matcher_->follow(cur_, p.e, p.n, x[Ekf::kPsi], hsig);
    p.cell = cur_.cell;
    p.arc_m = cur_.arc_m;
    p.lateral_m = cur_.lateral_m;
    p.confidence = confidence_;
    p.flags |= kPoseMatched;
    // The eye on the matched street, keeping the lateral offset within the
    // carriageway: at least kEyeInset inside its edge, where a driver sits
    // (an eye at the kerb faces the corner's wall mid-turn). Streets narrower
    // than twice that keep the eye on the centre line.
    constexpr double kEyeInset = 1.0;
    const float w = graph_->halfedge(cur_.cell).width;
    const double width = w > 0 ? w : 4.0;
    const double half = std::max(0.0, 0.5 * width - kEyeInset);
    const double lat = std::clamp(cur_.lateral_m, -half, half);
    const double hr = cur_.heading_rad;
    p.camera.eye_e = cur_.e + lat * std::cos(hr);  // right of a bearing h is (cos h, -sin h)
    p.camera.eye_n = cur_.n - lat * std::sin(hr);
    p.camera.heading_deg = ekf_.headingValid() ? p.heading_deg : hr / kDeg;
  } else {
    p.camera.eye_e = p.e;
    p.camera.eye_n = p.n;
    p.camera.heading_deg = p.heading_deg;
  }
  p.camera.eye_u = d_.eye_height_m;
  p.camera.pitch_deg = d_.camera_pitch_deg;
  if (matcher_) {
    p.settled_cell = matcher_->settled().cell;
    p.settled_t = matcher_->settledTime();
  }
  return p;
}

}  // namespace blvd::track
