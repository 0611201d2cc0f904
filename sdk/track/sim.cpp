#include "track/sim.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "core/math.h"
#include "core/rng.h"
#include "graph/route.h"
#include "track/lane.h"

namespace blvd::track {
namespace {
using core::kPi;
constexpr double kDeg = kPi / 180.0;

// Portable random numbers: mt19937_64's output sequence is fixed by the
// standard; the distributions are not, so they are written out here.
using core::Rng;

double wrap(double a) {
  a = std::fmod(a + kPi, 2 * kPi);
  if (a < 0) a += 2 * kPi;
  return a - kPi;
}
double bearing(glm::dvec2 d) {
  const double a = std::atan2(d.x, d.y);
  return a < 0 ? a + 2 * kPi : a;
}


// The route as one polyline with the cell of each segment (segment i ends at point i).
struct Path {
  std::vector<glm::dvec2> pts;
  std::vector<uint32_t> cell_of;
  std::vector<double> arc;
  std::vector<double> cell_start;  // arc at the start of the segment's cell, per point

  double length() const { return arc.empty() ? 0 : arc.back(); }
  size_t segmentAt(double s) const {
    size_t i = std::upper_bound(arc.begin(), arc.end(), s) - arc.begin();
    return std::clamp<size_t>(i, 1, pts.size() - 1);
  }
  glm::dvec2 at(double s) const {
    s = std::clamp(s, 0.0, length());
    const size_t i = segmentAt(s);
    const double seg = arc[i] - arc[i - 1];
    const double t = seg > 0 ? (s - arc[i - 1]) / seg : 0;
    return pts[i - 1] + (pts[i] - pts[i - 1]) * t;
  }
  glm::dvec2 dirAt(double s) const {
    s = std::clamp(s, 0.0, length());
    size_t i = segmentAt(s);
    // Skip degenerate segments.
    while (i + 1 < pts.size() && glm::length(pts[i] - pts[i - 1]) < 1e-6) ++i;
    const glm::dvec2 d = pts[i] - pts[i - 1];
    const double l = glm::length(d);
    return l > 0 ? d / l : glm::dvec2(0, 1);
  }
};

Path flatten(const graph::StreetGraph& g, const std::vector<uint32_t>& route) {
  Path p;
  for (uint32_t h : route) {
    const auto& e = g.halfedges[h];
    const double start = p.pts.empty() ? 0 : p.arc.back();
    for (uint32_t i = p.pts.empty() ? 0 : 1; i < e.pts_count; ++i) {
      const glm::dvec2 q = g.points[e.pts_begin + i];
      p.arc.push_back(p.pts.empty() ? 0 : p.arc.back() + glm::length(q - p.pts.back()));
      p.pts.push_back(q);
      p.cell_of.push_back(h);
      p.cell_start.push_back(start);
    }
  }
  return p;
}

struct State {
  double e, n, psi, v, psidot, s;
};

// Speed limit on a 1 m grid along the path: curvature over +-3 m limits the
// speed, then braking and acceleration limits (backward and forward passes).
class SpeedProfile {
 public:
  SpeedProfile(const Path& path, double L, const SimDesc& d) : vmax_(static_cast<size_t>(L) + 1) {
    const size_t ns = vmax_.size();
    for (size_t k = 0; k < ns; ++k) {
      const double s = static_cast<double>(k);
      const double turn = std::fabs(wrap(bearing(path.dirAt(s + 3)) - bearing(path.dirAt(s - 3))));
      const double kappa = turn / 6.0;
      vmax_[k] = std::clamp(kappa > 1e-6 ? std::sqrt(d.lat_accel / kappa) : d.cruise_mps, d.min_speed_mps, d.cruise_mps);
    }
    vmax_.back() = d.min_speed_mps;
    for (size_t k = ns - 1; k-- > 0;) vmax_[k] = std::min(vmax_[k], std::sqrt(vmax_[k + 1] * vmax_[k + 1] + 2 * d.decel));
    vmax_[0] = std::min(vmax_[0], 0.6 * d.cruise_mps);
    for (size_t k = 1; k < ns; ++k) vmax_[k] = std::min(vmax_[k], std::sqrt(vmax_[k - 1] * vmax_[k - 1] + 2 * d.accel));
  }
  size_t size() const { return vmax_.size(); }
  double at(double s) const {
    const size_t ns = vmax_.size();
    const double f = std::clamp(s, 0.0, static_cast<double>(ns - 1));
    const size_t k = std::min(static_cast<size_t>(f), ns - 2);  // ns >= 21: L >= 20
    const double u = f - static_cast<double>(k);
    return vmax_[k] * (1 - u) + vmax_[k + 1] * u;
  }

 private:
  std::vector<double> vmax_;
};

// The line the car aims for: the lane of the cell at s (lane.h: right of the
// centre on two-way streets, the centre on one-way streets) plus a lane wander
// on a 1 m grid, w[k+1] = a w[k] + sqrt(1 - a^2) sigma n, a = exp(-1 m /
// length) (its own random stream, so the other noises do not change). Pure
// pursuit smooths the step between cells.
class LaneLine {
 public:
  LaneLine(const graph::StreetGraph& g, const Path& path, double L, const SimDesc& d)
      : g_(g), path_(path), L_(L), lateral_m_(d.lateral_m), wander_(static_cast<size_t>(L) + 1, 0.0) {
    if (!(d.lane_wander_m > 0 && d.lane_wander_length_m > 0)) return;
    Rng rng_lane(d.seed * 0x9E3779B97F4A7C15ull + 4);
    const double a = std::exp(-1.0 / d.lane_wander_length_m);
    wander_[0] = d.lane_wander_m * rng_lane.gauss();
    for (size_t k = 1; k < wander_.size(); ++k)
      wander_[k] = a * wander_[k - 1] + std::sqrt(1 - a * a) * d.lane_wander_m * rng_lane.gauss();
  }
  glm::dvec2 at(double s) const {
    const glm::dvec2 dir = path_.dirAt(s);
    const uint32_t cell = path_.cell_of[path_.segmentAt(std::clamp(s, 0.0, path_.length()))];
    const size_t k = std::min(static_cast<size_t>(std::clamp(s, 0.0, L_)), wander_.size() - 1);
    const double lateral = laneOffset(g_.halfedges[cell], lateral_m_) + wander_[k];
    return path_.at(s) + glm::dvec2(dir.y, -dir.x) * lateral;
  }

 private:
  const graph::StreetGraph& g_;
  const Path& path_;
  double L_, lateral_m_;
  std::vector<double> wander_;
};

// The car's progress: the nearest point of the route, searching forward from
// segment `seg` (updated) up to 30 m past the last progress.
void advanceProgress(const Path& path, State& st, size_t& seg) {
  const glm::dvec2 p(st.e, st.n);
  double best = 1e300, best_s = st.s;
  size_t best_seg = seg;
  for (size_t i = seg; i < path.pts.size() && path.arc[i - 1] <= st.s + 30; ++i) {
    const glm::dvec2 a = path.pts[i - 1], b = path.pts[i];
    const glm::dvec2 ab = b - a;
    const double l2 = glm::dot(ab, ab);
    const double t = l2 > 0 ? std::clamp(glm::dot(p - a, ab) / l2, 0.0, 1.0) : 0.0;
    const double dist = glm::length(a + ab * t - p);
    if (dist < best - 1e-9) best = dist, best_s = path.arc[i - 1] + t * std::sqrt(l2), best_seg = i;
  }
  if (best_s > st.s) st.s = best_s, seg = best_seg;
}

// Integrates the vehicle from arc s0 to L: pure pursuit (Coulter 1992) toward
// a point a speed-dependent distance ahead on the lane line.
std::vector<State> drive(const Path& path, const LaneLine& lane, const SpeedProfile& profile, double s0, double L,
                         const SimDesc& d) {
  std::vector<State> states;
  State st{};
  const glm::dvec2 p0 = lane.at(s0);
  st.e = p0.x;
  st.n = p0.y;
  st.psi = bearing(path.dirAt(s0));
  st.v = d.start_speed_mps >= 0 ? d.start_speed_mps : profile.at(s0);
  st.s = s0;
  size_t seg = path.segmentAt(s0);
  const size_t max_steps = static_cast<size_t>(3600.0 / d.dt);
  while (st.s < L - 1.0 && states.size() < max_steps) {
    states.push_back(st);
    st.v += std::clamp(profile.at(st.s) - st.v, -d.decel * d.dt, d.accel * d.dt);
    const double look = std::max(6.0, 1.0 * st.v);
    const glm::dvec2 target = lane.at(st.s + look);
    const double alpha = wrap(bearing(target - glm::dvec2(st.e, st.n)) - st.psi);
    st.psidot = st.v * 2 * std::sin(alpha) / look;
    const double psim = st.psi + 0.5 * st.psidot * d.dt;
    st.e += st.v * d.dt * std::sin(psim);
    st.n += st.v * d.dt * std::cos(psim);
    st.psi = std::fmod(st.psi + st.psidot * d.dt + 2 * kPi, 2 * kPi);
    advanceProgress(path, st, seg);
  }
  states.push_back(st);
  return states;
}

// Duration, distance, where the car started and stopped, the outage window.
void describeDrive(const std::vector<State>& states, const Path& path, const SimDesc& d, SimTrace& out) {
  out.duration_s = static_cast<double>(states.size() - 1) * d.dt;
  out.start_e = states.front().e;
  out.start_n = states.front().n;
  out.start_heading_deg = states.front().psi / kDeg;
  const State& last = states.back();
  const size_t i = path.segmentAt(last.s);
  out.end_cell = path.cell_of[i];
  out.end_arc_m = last.s - path.cell_start[i];
  out.end_e = last.e;
  out.end_n = last.n;
  out.end_heading_deg = last.psi / kDeg;
  for (size_t k = 1; k < states.size(); ++k)
    out.distance_m += std::hypot(states[k].e - states[k - 1].e, states[k].n - states[k - 1].n);
  if (d.outage_s > 0 && out.duration_s > d.outage_s + 20) {
    out.outage_begin = std::floor(d.outage_at * out.duration_s);
    out.outage_end = out.outage_begin + d.outage_s;
  }
}

// The truth at one GNSS epoch.
SimSample truthAt(const State& st, double t, const Path& path) {
  SimSample smp;
  smp.t = t;
  smp.e = st.e;
  smp.n = st.n;
  smp.heading_deg = st.psi / kDeg;
  smp.speed_mps = st.v;
  const size_t i = path.segmentAt(st.s);
  smp.cell = path.cell_of[i];
  smp.arc_m = st.s - path.cell_start[i];
  return smp;
}

// The sensors: odometry every odo period, a GNSS epoch (truth, and a noisy
// fix unless dropped or in the outage) every GNSS period. Every random
// number is drawn whether or not the fix is kept, so dropping one fix does
// not change the noise of the others.
void sampleSensors(const std::vector<State>& states, const Path& path, const geo::LocalFrame& frame, const SimDesc& d,
                   SimTrace& out) {
  Rng rng_gnss(d.seed * 0x9E3779B97F4A7C15ull + 1), rng_drop(d.seed * 0x9E3779B97F4A7C15ull + 2),
      rng_odo(d.seed * 0x9E3779B97F4A7C15ull + 3);
  const size_t odo_every = std::max<size_t>(1, static_cast<size_t>(std::lround(1.0 / (d.odo_rate_hz * d.dt))));
  const size_t gnss_every = std::max<size_t>(1, static_cast<size_t>(std::lround(1.0 / (d.gnss_rate_hz * d.dt))));
  for (size_t k = 0; k < states.size(); ++k) {
    const State& st = states[k];
    const double t = static_cast<double>(k) * d.dt;
    if (k % odo_every == 0) {
      Odometry o;
      o.t = t;
      o.speed_mps = std::max(0.0, st.v * d.speed_scale + d.speed_noise * rng_odo.gauss());
      o.yaw_rate_dps = -st.psidot / kDeg + d.yaw_bias_dps + d.yaw_noise_dps * rng_odo.gauss();
      o.flags = kOdoSpeed | kOdoYawRate;
      out.odometry.push_back(o);
    }
    if (k == 0 || k % gnss_every != 0) continue;
    out.epochs.push_back(truthAt(st, t, path));
    const double ne = d.gnss_sigma_m * rng_gnss.gauss(), nn = d.gnss_sigma_m * rng_gnss.gauss();
    const double ve = st.v * std::sin(st.psi) + d.gnss_speed_sigma * rng_gnss.gauss();
    const double vn = st.v * std::cos(st.psi) + d.gnss_speed_sigma * rng_gnss.gauss();
    const bool dropped = rng_drop.uniform() < d.drop_fraction;
    const bool in_outage = t >= out.outage_begin && t < out.outage_end;
    const bool keep = !dropped && !in_outage;
    out.epoch_has_fix.push_back(keep ? 1 : 0);
    if (!keep) continue;
    GnssFix f;
    f.t = t;
    double h = 0;
    frame.reverse(geo::Enu{st.e + ne, st.n + nn, 0}, f.lat, f.lon, h);
    f.alt = h;
    f.speed_mps = static_cast<float>(std::hypot(ve, vn));
    f.track_deg = static_cast<float>(bearing(glm::dvec2(ve, vn)) / kDeg);
    f.hdop = 1.0f;
    f.h_acc_m = static_cast<float>(d.gnss_sigma_m * std::sqrt(2.0));
    f.mode = kGnssMode3D;
    f.flags = kGnssHasTime | kGnssHasLatLon | kGnssHasAlt | kGnssHasSpeed | kGnssHasTrack | kGnssHasHdop | kGnssHasHAcc;
    out.fixes.push_back(f);
  }
}

}  // namespace

std::vector<uint32_t> simRoute(const graph::StreetGraph& g, uint32_t cells, uint64_t seed, uint32_t first) {
  graph::RouteRules rules;
  rules.cells = cells;
  rules.seed = seed;
  rules.first = first;
  rules.revisit = false;
  rules.attempts = 16;
  return graph::seededRoute(g, rules);
}

SimTrace simulateDrive(const graph::StreetGraph& g, const geo::LocalFrame& frame, const SimDesc& d) {
  SimTrace out;
  out.route = simRoute(g, d.route_cells, d.seed, d.first_cell);
  const Path path = flatten(g, out.route);
  if (path.pts.size() < 2 || path.length() < 20 || d.dt <= 0) return out;
  const double L_route = path.length();
  // Where the drive ends: the route's end, or halfway along its last cell.
  const double L =
      d.park_mid_last_cell ? std::max(0.5 * (path.cell_start.back() + L_route), std::min(L_route, 21.0)) : L_route;
  const double s0 = d.first_cell < g.halfedges.size() ? std::clamp(d.start_arc_m, 0.0, std::max(0.0, L - 21.0)) : 0.0;
  const SpeedProfile profile(path, L, d);
  const LaneLine lane(g, path, L, d);
  const std::vector<State> states = drive(path, lane, profile, s0, L, d);
  describeDrive(states, path, d, out);
  sampleSensors(states, path, frame, d, out);
  return out;
}

}  // namespace blvd::track
