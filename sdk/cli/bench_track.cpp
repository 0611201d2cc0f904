// The tracking benchmark (bench_track.h says what each figure measures).
#include "cli/bench_track.h"

#include <GeographicLib/Geocentric.hpp>
#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "bake/bake.h"
#include "can/candump.h"
#include "capi/track_convert.h"
#include "core/math.h"
#include "cli/read_files.h"
#include "core/status.h"
#include "replay/replayer.h"
#include "sim/sim_feed.h"
#include "stream/city.h"
#include "track/lane.h"
#include "track/map_matcher.h"
#include "vehicle/dbc.h"
#include "vehicle/profile.h"

namespace blvd::cli {
namespace {

using core::Error;
using core::Status;

std::vector<std::vector<double>> readCsv(const std::string& path) {
  std::istringstream in(readFile(path));
  std::string line;
  std::getline(in, line);  // header
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::vector<double> r;
    std::istringstream ls(line);
    std::string f;
    while (std::getline(ls, f, ',')) r.push_back(std::stod(f));
    rows.push_back(r);
  }
  return rows;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const double idx = q * static_cast<double>(v.size() - 1);
  const size_t i = static_cast<size_t>(idx);
  const double f = idx - static_cast<double>(i);
  return i + 1 < v.size() ? v[i] * (1 - f) + v[i + 1] * f : v[i];
}

// One input in time order.
struct Input {
  double t;
  bool gnss;
  track::GnssFix fix;
  track::Odometry odo;
};

void sortInputs(std::vector<Input>& in) {
  std::stable_sort(in.begin(), in.end(), [](const Input& a, const Input& b) { return a.t < b.t; });
}

// ---------------------------------------------------------------------------
// Fusion on the comma2k19 RAV4 minute

struct RefPose {
  double t, e, n;
};

struct FusionResult {
  double err_p50 = NAN, err_p95 = NAN, raw_gnss_p50 = NAN;
  double drift_pct = NAN, drift_err_m = NAN, drift_max_err_m = NAN, drift_dist_m = NAN;
  size_t gnss = 0, odometry = 0, poses = 0;
  uint64_t rejected = 0;
};

FusionResult benchFusion(const std::string& data, double gnss_latency_s, const std::string& trace_path) {
  FusionResult res;
  // Reference pose, ECEF -> geodetic -> the local frame of its first pose.
  const auto pose_rows = readCsv(data + "/track/comma2k19_rav4_seg40_global_pose.csv");
  const GeographicLib::Geocentric& earth = GeographicLib::Geocentric::WGS84();
  double lat0, lon0, h0;
  earth.Reverse(pose_rows[0][3], pose_rows[0][4], pose_rows[0][5], lat0, lon0, h0);
  const geo::LocalFrame frame(lat0, lon0, 0);
  std::vector<RefPose> ref;
  for (const auto& r : pose_rows) {
    double lat, lon, h;
    earth.Reverse(r[3], r[4], r[5], lat, lon, h);
    const geo::Enu p = frame.forward(lat, lon, 0);
    ref.push_back({r[0], p.e, p.n});
  }
  auto refAt = [&](double t, double& e, double& n) {
    if (t < ref.front().t || t > ref.back().t) return false;
    size_t i = std::upper_bound(ref.begin(), ref.end(), t, [](double x, const RefPose& p) { return x < p.t; }) - ref.begin();
    i = std::clamp<size_t>(i, 1, ref.size() - 1);
    const double u = (t - ref[i - 1].t) / (ref[i].t - ref[i - 1].t);
    e = ref[i - 1].e + u * (ref[i].e - ref[i - 1].e);
    n = ref[i - 1].n + u * (ref[i].n - ref[i - 1].n);
    return true;
  };

  std::vector<Input> inputs;
  std::vector<double> raw;
  for (const auto& r : readCsv(data + "/track/comma2k19_rav4_seg40_gnss_ublox.csv")) {
    Input in{};
    in.t = r[0];
    in.gnss = true;
    in.fix.t = r[0];
    in.fix.lat = r[1];
    in.fix.lon = r[2];
    in.fix.speed_mps = static_cast<float>(r[3]);
    in.fix.alt = r[5];
    in.fix.track_deg = static_cast<float>(r[6]);
    in.fix.mode = track::kGnssMode3D;
    in.fix.flags = track::kGnssHasLatLon | track::kGnssHasAlt | track::kGnssHasSpeed | track::kGnssHasTrack;
    inputs.push_back(in);
    double e, n;
    const geo::Enu p = frame.forward(r[1], r[2], 0);
    if (refAt(r[0], e, n)) raw.push_back(std::hypot(p.e - e, p.n - n));
    ++res.gnss;
  }
  res.raw_gnss_p50 = percentile(raw, 0.5);

  // CAN: the Toyota profile over the candump, powertrain bus only.
  vehicle::Database db;
  std::string err;
  if (db.load(data + "/can/dbc/toyota_new_mc_pt_generated.dbc", err) != core::Status::Ok) throw core::Error(core::Status::Io, err);
  vehicle::ProfileDesc pd;
  pd.iface = "can0";
  vehicle::Profile profile;
  if (profile.create(pd, db, err) != core::Status::Ok) throw core::Error(core::Status::NotFound, err);
  std::istringstream log(readZstd(data + "/can/comma2k19_rav4_seg40_candump.log.zst"));
  can::CandumpReader reader;
  reader.attach(log, "comma2k19_rav4_seg40_candump.log");
  can::Record rec;
  vehicle::Odometry co;
  for (;;) {
    const auto r = reader.next(rec);
    if (r == can::CandumpReader::Result::End || r == can::CandumpReader::Result::IoError) break;
    if (r != can::CandumpReader::Result::Frame || !profile.consume(rec.frame, co)) continue;
    Input in{};
    in.t = co.t;
    in.odo.t = co.t;
    if (co.updated & vehicle::kOdoSpeed) in.odo.flags |= track::kOdoSpeed, in.odo.speed_mps = co.speed_mps;
    if (co.updated & vehicle::kOdoYawRate) in.odo.flags |= track::kOdoYawRate, in.odo.yaw_rate_dps = co.yaw_rate_dps;
    if (co.updated & vehicle::kOdoWheelSpeeds) {
      in.odo.flags |= track::kOdoWheelSpeeds;
      std::memcpy(in.odo.wheel_speeds_mps, co.wheel_speeds_mps, sizeof co.wheel_speeds_mps);
    }
    if (co.gear == vehicle::Gear::Reverse) in.odo.flags |= track::kOdoGear, in.odo.reverse = true;
    if (!(in.odo.flags & (track::kOdoSpeed | track::kOdoYawRate | track::kOdoWheelSpeeds))) continue;
    inputs.push_back(in);
    ++res.odometry;
  }
  sortInputs(inputs);

  double first_gnss = 1e300;
  for (const auto& in : inputs)
    if (in.gnss) first_gnss = std::min(first_gnss, in.t);

  auto run = [&](double withhold_after, std::vector<double>& errs, std::vector<double>& err_t) {
    track::TrackerDesc desc;
    desc.gnss_latency_s = gnss_latency_s;
    track::Tracker tr(frame, nullptr, desc);
    FILE* trace = nullptr;
    if (!trace_path.empty()) {
      trace = std::fopen((trace_path + (withhold_after < 1e299 ? "-dr.csv" : ".csv")).c_str(), "w");
      if (trace) std::fprintf(trace, "t,ref_e,ref_n,e,n,heading_deg,speed_mps,bias_dps,sigma_m\n");
    }
    size_t k = 0;
    for (const RefPose& rp : ref) {
      for (; k < inputs.size() && inputs[k].t <= rp.t; ++k) {
        if (inputs[k].gnss) {
          if (inputs[k].t <= withhold_after) tr.feedGnss(inputs[k].fix);
        } else {
          tr.feedOdometry(inputs[k].odo);
        }
      }
      const track::Pose& p = tr.update(rp.t);
      if (trace)
        std::fprintf(trace, "%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.4f,%.3f\n", rp.t, rp.e, rp.n, p.e, p.n, p.heading_deg,
                     p.speed_mps, tr.filter().bias() * 57.29577951308232, p.pos_sigma_m);
      if (!(p.flags & track::kPoseValid) || rp.t < first_gnss + 1.0) continue;
      errs.push_back(std::hypot(p.e - rp.e, p.n - rp.n));
      err_t.push_back(rp.t);
    }
    if (trace) std::fclose(trace);
    return tr.stats().gnss_rejected;
  };
  std::vector<double> errs, err_t;
  res.rejected = run(1e300, errs, err_t);
  res.err_p50 = percentile(errs, 0.5);
  res.err_p95 = percentile(errs, 0.95);
  res.poses = errs.size();

  // Dead reckoning: GNSS withheld for the last 30 s of the reference.
  const double t_cut = ref.back().t - 30.0;
  std::vector<double> derrs, derr_t;
  run(t_cut, derrs, derr_t);
  double dist = 0, max_err = 0;
  for (size_t i = 1; i < ref.size(); ++i)
    if (ref[i].t > t_cut) dist += std::hypot(ref[i].e - ref[i - 1].e, ref[i].n - ref[i - 1].n);
  for (size_t i = 0; i < derrs.size(); ++i)
    if (derr_t[i] > t_cut) max_err = std::max(max_err, derrs[i]);
  res.drift_err_m = derrs.empty() ? NAN : derrs.back();
  res.drift_max_err_m = max_err;
  res.drift_dist_m = dist;
  res.drift_pct = 100.0 * res.drift_err_m / dist;
  return res;
}

// ---------------------------------------------------------------------------
// Map matching on Monaco, from simulated NMEA + candump parsed by the adapters

struct MatchResult {
  size_t epochs = 0, on_cell = 0, fix_epochs = 0, fix_on_cell = 0, settled = 0, settled_ok = 0;
  size_t warm_epochs = 0, warm_on_cell = 0;    // after the first 10 s of each drive
  size_t inner_epochs = 0, inner_on_cell = 0;  // truth at least 2 m from both ends of its cell
  size_t drives = 0, drives_chained = 0, drives_resumed = 0;
  double km = 0;
  uint64_t breaks = 0, steps = 0, gnss = 0, odometry = 0, nmea_bytes = 0, can_frames = 0, bad_lines = 0;
  std::vector<track::MatchObservation> observations;
  std::vector<size_t> drive_starts;
};

struct MatchSetup {
  const stream::City* city;
  const vehicle::Profile* profile;
  std::string dbc_path;
  uint32_t routes, route_cells;
  track::TrackerDesc tracker;
  double lane_wander_m = -1;  // TrackBenchOptions::sim_lane_wander_m
  bool oracle_calibration = false;
};

// How the pose's cell relates to the true one, for the trace: same, next (a
// successor of the truth: the pose is ahead), previous, sibling (another
// successor of the same predecessor: the other branch of a fork), twin (the
// other direction), none (no pose cell) or other.
const char* cellRelation(const graph::StreetGraph& g, uint32_t est, uint32_t truth) {
  if (est == truth) return "same";
  if (est >= g.cellCount()) return "none";
  if (g.halfedges[truth].twin == est) return "twin";
  for (const uint32_t* s = g.successors.begin(truth); s != g.successors.end(truth); ++s)
    if (*s == est) return "next";
  for (const uint32_t* s = g.predecessors.begin(truth); s != g.predecessors.end(truth); ++s) {
    if (*s == est) return "previous";
    for (const uint32_t* t = g.successors.begin(*s); t != g.successors.end(*s); ++t)
      if (*t == est) return "sibling";
  }
  return "other";
}

// How one drive follows the one before (the simulated car is the same in every drive).
struct DriveChain {
  // Every drive after the first starts from the odometry calibration (wheel-speed
  // scale, yaw-rate bias) the previous drive's filter ended with, as a host that
  // stores it at key-off would.
  bool calibrated = false;
  // Each drive ends parked halfway along its last cell and the next one pulls
  // away from there (sim park_mid_last_cell, first_cell, start_arc_m); the
  // first starts from a standstill on a seeded street.
  bool chained = false;
  // With chained: the tracker starts from the previous drive's last pose
  // (Tracker::setStartPose), as a host that stores it at key-off would.
  bool resume_pose = false;
};

// Where the last drive ended, carried to the next one when drives are chained.
struct ChainState {
  uint32_t end_cell = track::kNoCell;  // where the car stopped
  double end_arc = 0;
  bool have_start = false;             // the pose the tracker ended with
  track::StartPose start;
  track::OdometryCalibration cal;
  bool have_cal = false;
};

// Drive r's simulated feed: a seeded street, or (chained) pulling away from
// where the last drive parked; towed to a seeded street when no route of half
// the cells goes on from there. False for a drive the graph cannot hold.
bool driveFeed(const MatchSetup& ms, double sigma, const DriveChain& chain, uint32_t r, ChainState& cs,
               sim::FeedDesc& fd, sim::Feed& feed, bool& resumed) {
  const graph::StreetGraph& g = ms.city->graph();
  fd.drive.seed = 1000 + r;
  fd.drive.route_cells = ms.route_cells;
  fd.drive.gnss_sigma_m = sigma;
  if (ms.lane_wander_m >= 0) fd.drive.lane_wander_m = ms.lane_wander_m;
  if (chain.chained) {
    fd.drive.start_speed_mps = 0;
    fd.drive.park_mid_last_cell = true;
    fd.drive.first_cell = cs.end_cell;
    fd.drive.start_arc_m = cs.end_arc;
  }
  std::string err;
  blvd_status fst = sim::makeFeed(g, ms.city->frame(), *ms.profile, fd, feed, err);
  resumed = chain.resume_pose && cs.have_start;
  if (fd.drive.first_cell != track::kNoCell && (fst == BLVD_ERR_NOT_FOUND || 2 * feed.route.size() < ms.route_cells)) {
    fd.drive.first_cell = track::kNoCell;
    resumed = false;
    fst = sim::makeFeed(g, ms.city->frame(), *ms.profile, fd, feed, err);
  }
  cs.end_cell = track::kNoCell;
  cs.have_start = false;
  if (fst == BLVD_ERR_NOT_FOUND) return false;
  if (fst != BLVD_OK) throw Error(Status::Internal, err);
  return true;
}

// The device bytes of a drive, parsed back by the adapters as a host's would be.
void openReplay(const MatchSetup& ms, const sim::FeedDesc& fd, bool with_odometry, std::istringstream& nmea,
                std::istringstream& can_log, replay::Replayer& replayer) {
  replay::ReplayDesc rd;
  rd.nmea_path = "sim-" + std::to_string(fd.drive.seed) + ".nmea";
  rd.nmea_stream = &nmea;
  if (with_odometry) {
    rd.candump_path = "sim-" + std::to_string(fd.drive.seed) + ".log";
    rd.candump_stream = &can_log;
    rd.dbc_path = ms.dbc_path;
    rd.vehicle = "toyota";
    rd.has_offset = true;  // both streams are on the simulator's UTC clock
    rd.offset_s = 0;
  }
  rd.strict = true;  // the simulator's output must parse without a single bad line
  std::string err;
  if (replayer.open(rd, err) != BLVD_OK) throw Error(Status::Io, err);
}

const char* kTraceHeader =
    "drive,t,fix,true_cell,true_arc,true_len,cell,arc,conf,err_m,sigma_m,true_e,true_n,e,n,heading,"
    "true_heading,est_arc_on_true,est_dist_on_true,map_aids,true_dist_on_est,est_cell_heading,yaw_bias_dps,"
    "odo_scale,true_h0,true_h1,fix_e,fix_n,nees,sigma_along,aid_suspensions,head_cell,true_lat,est_lat,lane_m,kappa,"
    "aid_lowconf,aid_disagree,aid_ambiguous,relation\n";

// One epoch of the --trace CSV: the truth, the pose, and the filter's and
// matcher's state behind it.
void traceRow(FILE* tf, const graph::StreetGraph& g, uint32_t r, const sim::Feed& feed, const sim::TruthRow& s,
              const track::Pose& p, const track::Tracker& tr) {
  const track::CellPoint q = tr.matcher()->project(s.cell, p.e, p.n);
  const track::CellPoint qe = tr.matcher()->project(p.cell, s.e, s.n);  // the truth on the pose's cell
  const track::CellPoint qt = tr.matcher()->project(s.cell, s.e, s.n);  // the truth on its own cell
  const glm::dvec2 d0 = graph::cellDirection(g, s.cell, false), d1 = graph::cellDirection(g, s.cell, true);
  // The raw fix of this epoch's HMM step (empty without one), and the normalised estimation
  // error of the filter, err^T P^-1 err over east and north (chi-square with 2 dof, mean 2,
  // for a consistent filter; Bar-Shalom, Li & Kirubarajan 2001, §5.4.2).
  const track::MatchObservation& ob = tr.matcher()->lastObservation();
  char fix_en[64] = ",";
  if (s.fix && ob.fix_sigma_m > 0 && std::fabs(ob.t - s.t) < 1e-6) std::snprintf(fix_en, sizeof fix_en, "%.2f,%.2f", ob.fix_e, ob.fix_n);
  const double pee = tr.filter().cov(0, 0), pnn = tr.filter().cov(1, 1), pen = tr.filter().cov(0, 1);
  const double det = pee * pnn - pen * pen, ee = p.e - s.e, en = p.n - s.n;
  const double nees = det > 0 ? (ee * ee * pnn - 2 * ee * en * pen + en * en * pee) / det : -1.0;
  // The filter's sigma along the true heading (its claimed along-track uncertainty).
  const double th = s.heading_deg * core::kDegToRad, ue = std::sin(th), un = std::cos(th);
  const double sigma_along = std::sqrt(std::max(0.0, ue * ue * pee + 2 * ue * un * pen + un * un * pnn));
  const double deg = core::kRadToDeg;
  std::fprintf(tf, "%u,%.2f,%d,%u,%.2f,%.2f,%u,%.2f,%.3f,%.2f,%.2f,%.2f,%.2f,%.2f,%.2f,%.1f,%.1f,%.2f,%.2f,%llu,%.2f,%.1f,%.3f,%.5f,%.1f,%.1f,%s,%.2f,%.3f,%llu,%d,%.3f,%.3f,%.2f,%.5f,%llu,%llu,%llu,%s\n", r,
               s.t - feed.start_unix, s.fix ? 1 : 0, s.cell, s.arc_m, g.halfedges[s.cell].length, p.cell, p.arc_m,
               p.confidence, std::hypot(p.e - s.e, p.n - s.n), p.pos_sigma_m, s.e, s.n, p.e, p.n, p.heading_deg,
               s.heading_deg, q.arc_m, q.dist_m, static_cast<unsigned long long>(tr.stats().map_aids),
               qe.cell == track::kNoCell ? -1.0 : qe.dist_m, qe.heading_rad * deg, tr.filter().bias() * deg,
               tr.filter().odometryScale(), std::atan2(d0.x, d0.y) * deg, std::atan2(d1.x, d1.y) * deg, fix_en, nees,
               sigma_along, static_cast<unsigned long long>(tr.stats().map_aid_suspensions),
               tr.matcher()->head().cell == track::kNoCell ? -1 : static_cast<int>(tr.matcher()->head().cell),
               qt.lateral_m, q.lateral_m, track::laneOffset(g.halfedges[s.cell], 1.75),
               std::fabs(tr.filter().speed()) > 1 ? tr.filter().turnRate() / tr.filter().speed() : 0.0,
               static_cast<unsigned long long>(tr.stats().map_aid_low_confidence),
               static_cast<unsigned long long>(tr.stats().map_aid_disagreeing),
               static_cast<unsigned long long>(tr.stats().map_aid_ambiguous), cellRelation(g, p.cell, s.cell));
}

// One epoch's score: on the true cell (all, with a fix, warm, inner), and the
// fixed-lag decision against the truth of its time.
void scoreEpoch(const graph::StreetGraph& g, const sim::Feed& feed, const sim::TruthRow& s, const track::Pose& p,
                const std::vector<std::pair<double, uint32_t>>& truth, MatchResult& res) {
  ++res.epochs;
  const bool ok = p.cell == s.cell;
  res.on_cell += ok;
  if (s.fix) ++res.fix_epochs, res.fix_on_cell += ok;
  if (s.t - feed.start_unix > 10.0) ++res.warm_epochs, res.warm_on_cell += ok;
  if (s.arc_m >= 2.0 && g.halfedges[s.cell].length - s.arc_m >= 2.0) ++res.inner_epochs, res.inner_on_cell += ok;
  if (p.settled_cell == track::kNoCell) return;
  for (auto it = truth.rbegin(); it != truth.rend(); ++it)
    if (std::fabs(it->first - p.settled_t) < 1e-6) {
      ++res.settled;
      res.settled_ok += it->second == p.settled_cell;
      return;
    }
}

// The adapters' events in time order, into a tracker.
class EventPump {
 public:
  EventPump(replay::Replayer& replayer, track::Tracker& tr, MatchResult& res) : replayer_(replayer), tr_(tr), res_(res) {}
  // Feeds every event up to time t (all of them with t infinite); `step`
  // after each. `count`: into the result's gnss and odometry counts (the
  // drive's epochs), or not (what follows its last epoch).
  template <typename Step>
  void until(double t, Step&& step, bool count = true) {
    while (!done_) {
      if (!have_) {
        const replay::Replayer::Step st = replayer_.next(ev_);
        if (st == replay::Replayer::Step::End) {
          done_ = true;
          return;
        }
        if (st == replay::Replayer::Step::Error) throw Error(Status::Corrupt, replayer_.error());
        have_ = true;
      }
      if (ev_.t > t + 1e-6) return;
      have_ = false;
      if (ev_.type == replay::EventType::Gnss) {
        tr_.feedGnss(capi::toTrack(ev_.gnss));
        res_.gnss += count;
      } else {
        tr_.feedOdometry(capi::toTrack(ev_.odometry));
        res_.odometry += count;
        // Keep the ring from overflowing: update between odometry bursts.
        if (++fed_ % 64 == 0) tr_.update(ev_.t);
      }
      step();
    }
  }

 private:
  replay::Replayer& replayer_;
  track::Tracker& tr_;
  MatchResult& res_;
  replay::Event ev_;
  bool have_ = false, done_ = false;
  uint64_t fed_ = 0;
};

// Key-off: where the car stopped and the pose the tracker ended with, for the next drive.
void keyOff(const MatchSetup& ms, const sim::Feed& feed, track::Tracker& tr, ChainState& cs) {
  const track::Pose& p = tr.update(feed.start_unix + feed.duration_s);
  cs.end_cell = feed.end_cell;
  cs.end_arc = feed.end_arc_m;
  if (!(p.flags & track::kPoseValid)) return;
  double h = 0;
  ms.city->frame().reverse(geo::Enu{p.e, p.n, 0}, cs.start.lat, cs.start.lon, h);
  cs.start.heading_deg = p.heading_deg;
  cs.start.sigma_m = p.pos_sigma_m;
  cs.start.heading_sigma_deg = p.heading_sigma_deg;
  cs.have_start = (p.flags & track::kPoseHeadingValid) != 0;
}

MatchResult benchMatching(const MatchSetup& ms, double sigma, bool with_odometry, const std::string& trace_path,
                          DriveChain chain = DriveChain{}) {
  MatchResult res;
  ChainState cs;
  FILE* tf = trace_path.empty() ? nullptr : std::fopen(trace_path.c_str(), "w");
  if (tf) std::fputs(kTraceHeader, tf);
  const graph::StreetGraph& g = ms.city->graph();
  for (uint32_t r = 0; r < ms.routes; ++r) {
    sim::FeedDesc fd;
    sim::Feed feed;
    bool resumed = false;
    if (!driveFeed(ms, sigma, chain, r, cs, fd, feed, resumed)) continue;
    ++res.drives;
    res.km += feed.distance_m / 1000.0;
    res.nmea_bytes += feed.nmea.size();
    res.can_frames += feed.frames.size();
    std::istringstream nmea(feed.nmea), can_log(with_odometry ? sim::candumpText(feed, "can0") : std::string());
    replay::Replayer replayer;
    openReplay(ms, fd, with_odometry, nmea, can_log, replayer);

    track::Tracker tr(ms.city->frame(), &g, ms.tracker);
    if (ms.oracle_calibration) {
      track::OdometryCalibration truth;
      truth.speed_scale = fd.drive.speed_scale;
      truth.yaw_bias_rad_s = fd.drive.yaw_bias_dps * capi::kRadPerDeg;  // sigmas 0: raised to the floors
      if (!tr.setCalibration(truth)) throw Error(Status::Internal, "calibration refused");
    } else if (chain.calibrated && cs.have_cal && !tr.setCalibration(cs.cal)) {
      throw Error(Status::Internal, "calibration refused");
    }
    res.drives_chained += fd.drive.first_cell != track::kNoCell;
    res.drives_resumed += resumed;
    if (resumed) {
      cs.start.t = feed.start_unix;  // key-on: the car has not moved since the stored pose
      if (!tr.setStartPose(cs.start)) throw Error(Status::Internal, "start pose refused");
    }
    res.drive_starts.push_back(res.observations.size());
    uint64_t steps = 0;
    const auto noteStep = [&] {
      if (tr.matcher()->stats().steps == steps) return;
      steps = tr.matcher()->stats().steps;
      res.observations.push_back(tr.matcher()->lastObservation());
    };
    EventPump pump(replayer, tr, res);
    std::vector<std::pair<double, uint32_t>> truth;  // (t, cell) per epoch, for the settled check
    for (const sim::TruthRow& s : feed.truth) {
      truth.emplace_back(s.t, s.cell);
      pump.until(s.t, noteStep);
      const track::Pose& p = tr.update(s.t);
      noteStep();
      if (tf) traceRow(tf, g, r, feed, s, p, tr);
      scoreEpoch(g, feed, s, p, truth, res);
    }
    res.bad_lines += replayer.stats().bad_lines;
    if (chain.chained) {
      // The rest of the drive after its last epoch, then the pose where the car stopped.
      pump.until(std::numeric_limits<double>::infinity(), [] {}, false);
      keyOff(ms, feed, tr, cs);
    }
    if (chain.calibrated) {
      cs.cal = tr.calibration();
      cs.have_cal = true;
    }
    res.breaks += tr.stats().match.breaks;
    res.steps += tr.stats().match.steps;
  }
  if (tf) std::fclose(tf);
  return res;
}

// Replays recorded observations through fresh matchers, timing each step.
double timeSteps(const graph::StreetGraph& g, const std::vector<const MatchResult*>& runs, int repeats) {
  std::vector<double> us;
  track::MapMatcher m(g);
  for (int rep = 0; rep < repeats; ++rep)
    for (const MatchResult* r : runs)
      for (size_t d = 0; d < r->drive_starts.size(); ++d) {
        m.reset();
        const size_t end = d + 1 < r->drive_starts.size() ? r->drive_starts[d + 1] : r->observations.size();
        for (size_t i = r->drive_starts[d]; i < end; ++i) {
          const auto t0 = std::chrono::steady_clock::now();
          m.step(r->observations[i]);
          const auto t1 = std::chrono::steady_clock::now();
          us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
        }
      }
  return percentile(us, 0.5);
}

double share(size_t a, size_t b) { return b ? static_cast<double>(a) / static_cast<double>(b) : NAN; }

nlohmann::json matchJson(const MatchResult& r) {
  return {{"drives", r.drives},
          {"drives_chained", r.drives_chained},
          {"drives_resumed", r.drives_resumed},
          {"km", r.km},
          {"epochs", r.epochs},
          {"on_cell", share(r.on_cell, r.epochs)},
          {"on_cell_fix_epochs", share(r.fix_on_cell, r.fix_epochs)},
          {"on_cell_after_10s", share(r.warm_on_cell, r.warm_epochs)},
          {"on_cell_2m_from_junctions", share(r.inner_on_cell, r.inner_epochs)},
          {"settled_on_cell", share(r.settled_ok, r.settled)},
          {"hmm_steps", r.steps},
          {"hmm_breaks", r.breaks},
          {"gnss_fixes_parsed", r.gnss},
          {"odometry_events_parsed", r.odometry},
          {"nmea_bytes", r.nmea_bytes},
          {"can_frames", r.can_frames},
          {"bad_lines", r.bad_lines}};
}

bool isFile(const std::string& p) {
  struct stat st {};
  return ::stat(p.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

// tests/data and data/ from the working directory or one of its parents (the
// repository root, or a build folder inside it), else the source tree this was
// built from.
std::string findDir(const std::string& rel, const std::string& probe) {
  std::string up;
  for (int i = 0; i < 4; ++i, up += "../")
    if (isFile(up + rel + "/" + probe)) return up + rel;
#ifdef BLVD_SOURCE_DIR
  if (isFile(std::string(BLVD_SOURCE_DIR) + "/" + rel + "/" + probe)) return std::string(BLVD_SOURCE_DIR) + "/" + rel;
#endif
  throw Error(Status::NotFound, "cannot find " + rel + "/" + probe +
                                    " from the working directory; run from the repository or give --data / --package");
}

}  // namespace

std::string benchPackage(const std::string& osm, bool quiet) {
  struct stat src {};
  if (::stat(osm.c_str(), &src) != 0) throw Error(Status::Io, osm + ": cannot open");
  const char* tmp = std::getenv("TMPDIR");
  // The cache name carries the source's size and time, so a changed extract is baked again.
  const std::string path = std::string(tmp && *tmp ? tmp : "/tmp") + "/blvd-bench-track-" +
                           std::to_string(static_cast<long long>(src.st_size)) + "-" +
                           std::to_string(static_cast<long long>(src.st_mtime)) + ".blvd";
  if (isFile(path)) return path;
  bake::BakeOptions bo;
  bo.quiet = true;
  bo.impostor.mode = bake::ImpostorMode::None;  // tracking needs the street graph only
  if (!quiet) std::fprintf(stderr, "blvd bench track: baking %s (no impostors) into %s\n", osm.c_str(), path.c_str());
  const std::string part = path + ".part";
  bake::bakeCity(osm, part, bo);
  if (std::rename(part.c_str(), path.c_str()) != 0) throw Error(Status::Io, path + ": cannot write");
  return path;
}

nlohmann::json runTrackBench(const TrackBenchOptions& opt) {
  const std::string data = opt.data_dir.empty() ? findDir("tests/data", "can/dbc/toyota_new_mc_pt_generated.dbc")
                                                : opt.data_dir;
  std::string package = opt.package;
  if (package.empty())
    package = benchPackage(opt.osm.empty() ? findDir("data/osm", "monaco-geofabrik-2026.osm.pbf") +
                                                 "/monaco-geofabrik-2026.osm.pbf"
                                           : opt.osm,
                           opt.quiet);
  const bool quick = opt.match_only || opt.match_low_only;
  const FusionResult fu = quick ? FusionResult{} : benchFusion(data, opt.gnss_latency_s, opt.trace_prefix);

  stream::City city;
  std::string err;
  if (city.open(package, err) != core::Status::Ok) throw Error(Status::Io, err);
  MatchSetup ms;
  ms.city = &city;
  ms.dbc_path = data + "/can/dbc/toyota_new_mc_pt_generated.dbc";
  vehicle::Database db;
  if (db.load(ms.dbc_path, err) != Status::Ok) throw Error(Status::Io, err);
  vehicle::Profile profile;
  if (profile.create(vehicle::ProfileDesc{}, db, err) != Status::Ok) throw Error(Status::NotFound, err);
  ms.profile = &profile;
  ms.routes = opt.routes;
  ms.route_cells = opt.route_cells;
  ms.tracker = opt.tracker;
  ms.lane_wander_m = opt.sim_lane_wander_m;
  ms.oracle_calibration = opt.oracle_calibration;
  const std::string& tp = opt.trace_prefix;
  const MatchResult m5 = benchMatching(ms, opt.sigma_low, true, tp.empty() ? "" : tp + "-match5.csv");
  const MatchResult m15 =
      opt.match_low_only ? MatchResult{} : benchMatching(ms, opt.sigma_high, true, tp.empty() ? "" : tp + "-match15.csv");
  constexpr DriveChain kCalibrated{true, false, false}, kChained{false, true, false}, kResumed{true, true, true};
  const MatchResult c5 = benchMatching(ms, opt.sigma_low, true, tp.empty() ? "" : tp + "-match5-calibrated.csv", kCalibrated);
  const MatchResult c15 = opt.match_low_only ? MatchResult{}
                                             : benchMatching(ms, opt.sigma_high, true,
                                                             tp.empty() ? "" : tp + "-match15-calibrated.csv", kCalibrated);
  // Drives that follow each other (each starts where the last one stopped), tracked
  // cold and resumed from the last pose and calibration of the drive before.
  const MatchResult h5 = benchMatching(ms, opt.sigma_low, true, tp.empty() ? "" : tp + "-match5-chained.csv", kChained);
  const MatchResult r5 = benchMatching(ms, opt.sigma_low, true, tp.empty() ? "" : tp + "-match5-resumed.csv", kResumed);
  const MatchResult h15 = opt.match_low_only ? MatchResult{}
                                             : benchMatching(ms, opt.sigma_high, true,
                                                             tp.empty() ? "" : tp + "-match15-chained.csv", kChained);
  const MatchResult r15 = opt.match_low_only ? MatchResult{}
                                             : benchMatching(ms, opt.sigma_high, true,
                                                             tp.empty() ? "" : tp + "-match15-resumed.csv", kResumed);
  const MatchResult g5 = quick ? MatchResult{} : benchMatching(ms, opt.sigma_low, false, tp.empty() ? "" : tp + "-gnss5.csv");
  const MatchResult g15 = quick ? MatchResult{} : benchMatching(ms, opt.sigma_high, false, tp.empty() ? "" : tp + "-gnss15.csv");
  const double us = quick ? NAN : timeSteps(city.graph(), {&m5, &m15}, 3);
  const track::MapMatcher probe(city.graph());

  const double on5 = share(m5.on_cell, m5.epochs), on15 = share(m15.on_cell, m15.epochs);
  nlohmann::json j;
  j["on_cell_sigma5"] = on5;
  j["on_cell_sigma15"] = on15;
  // The same drives with the odometry calibration carried from one drive to the next.
  j["on_cell_sigma5_calibrated"] = share(c5.on_cell, c5.epochs);
  j["on_cell_sigma15_calibrated"] = share(c15.on_cell, c15.epochs);
  // Chained drives (each starts where the previous one stopped), tracked cold and
  // resumed from the previous drive's last pose and calibration (key-off state).
  j["on_cell_sigma5_chained"] = share(h5.on_cell, h5.epochs);
  j["on_cell_sigma5_resumed"] = share(r5.on_cell, r5.epochs);
  j["on_cell_sigma15_chained"] = share(h15.on_cell, h15.epochs);
  j["on_cell_sigma15_resumed"] = share(r15.on_cell, r15.epochs);
  j["update_us_p50"] = us;
  j["fusion_err_m_p50"] = fu.err_p50;
  j["dr_drift_pct"] = fu.drift_pct;
  j["targets"] = {{"on_cell_sigma5", {{"min", 0.99}, {"met", on5 >= 0.99}}},
                  {"on_cell_sigma15", {{"min", 0.95}, {"met", on15 >= 0.95}}},
                  {"update_us_p50", {{"max", 20}, {"met", us <= 20}}},
                  {"fusion_err_m_p50", {{"max", 1.5}, {"met", fu.err_p50 <= 1.5}}},
                  {"dr_drift_pct", {{"max", 2}, {"met", fu.drift_pct <= 2}}}};
  nlohmann::json d;
  d["package"] = package;
  d["fusion_err_m_p95"] = fu.err_p95;
  d["gnss_raw_err_m_p50"] = fu.raw_gnss_p50;
  d["fusion_poses"] = fu.poses;
  d["fusion_gnss_fixes"] = fu.gnss;
  d["fusion_odometry_samples"] = fu.odometry;
  d["fusion_gnss_rejected"] = fu.rejected;
  d["dr_err_end_m"] = fu.drift_err_m;
  d["dr_err_max_m"] = fu.drift_max_err_m;
  d["dr_distance_m"] = fu.drift_dist_m;
  d["gnss_latency_s"] = opt.gnss_latency_s;
  d["gnss_sigma_low_m"] = opt.sigma_low;
  d["gnss_sigma_high_m"] = opt.sigma_high;
  d["match_sigma5"] = matchJson(m5);
  d["match_sigma15"] = matchJson(m15);
  d["match_sigma5_calibrated"] = matchJson(c5);
  d["match_sigma15_calibrated"] = matchJson(c15);
  d["match_sigma5_chained"] = matchJson(h5);
  d["match_sigma5_resumed"] = matchJson(r5);
  d["match_sigma15_chained"] = matchJson(h15);
  d["match_sigma15_resumed"] = matchJson(r15);
  d["match_sigma5_gnss_only"] = matchJson(g5);
  d["match_sigma15_gnss_only"] = matchJson(g15);
  d["graph_cells"] = city.graph().cellCount();
  d["index_bytes"] = probe.indexBytes();
  d["matcher_bytes"] = probe.bytes();
  j["detail"] = d;
  return j;
}

}  // namespace blvd::cli
