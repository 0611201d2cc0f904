// The tracking benchmark of issue 5 (`blvd bench track` can print the same):
//
//   fusion_err_m_p50   comma2k19 RAV4 minute: u-blox fixes (stamped on arrival, no
//                      accuracy in the log) + CAN speed and yaw rate (the candump through
//                      adapters/can's Toyota profile) fused by the EKF; median distance
//                      to comma's reference pose at its 20 Hz frame times. Target <= 1.5 m.
//   dr_drift_pct       the same with the GNSS of the last 30 s withheld: position error
//                      at the end / distance driven in those 30 s. Target <= 2 %.
//   on_cell_sigma5     Monaco (the fixture package): drives simulated by track/sim.h
//   on_cell_sigma15    (50 seeded routes of 60 cells), 1 Hz fixes with noise sigma 5 m /
//                      15 m per axis, 10 % dropped, one 20 s outage, 50 Hz odometry with
//                      scale, bias and noise; the share of 1 Hz epochs (the dropped and the
//                      outage epochs included, the first seconds included) whose pose is
//                      on the true cell. Targets >= 0.99 / >= 0.95.
//   update_us_p50      median wall time of one map-matching step (MapMatcher::step),
//                      replaying the drives' observations (steady_clock per step, 3
//                      passes). Target <= 20 us.
// `targets` says which targets are met; `detail` has the context (GNSS-only matching,
// the share after a 10 s warm-up and away from junctions, the fixed-lag decisions, ...).
//
// Usage: bench_track --package PKG --data TESTS_DATA_DIR [--routes N] [--check]
//          [--min-on-cell5 X] [--min-on-cell15 X] [--no-timing-check] [--trace PREFIX]
//          [--gnss-latency S] [--map-aid-sigma S] [--map-aid-confidence C] [--lane-offset M]
//          [--ambiguity K]
// Prints one JSON object. --check exits 1 when a target is missed (the on-cell
// targets can be lowered with --min-on-cell5/15); --trace writes CSVs per pose.
#include <GeographicLib/Geocentric.hpp>
#include <zstd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "can/candump.h"
#include "common/test_files.h"
#include "can/dbc.h"
#include "can/profile.h"
#include "stream/city.h"
#include "track/sim.h"
#include "track/tracker.h"

using namespace blvd;

namespace {

using blvd::test::readFile;
using blvd::test::readZstd;

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
  can::Database db;
  std::string err;
  if (db.load(data + "/can/dbc/toyota_new_mc_pt_generated.dbc", err) != BLVD_OK) throw std::runtime_error(err);
  can::ProfileDesc pd;
  pd.iface = "can0";
  can::Profile profile;
  if (profile.create(pd, db, err) != BLVD_OK) throw std::runtime_error(err);
  std::istringstream log(readZstd(data + "/can/comma2k19_rav4_seg40_candump.log.zst"));
  can::CandumpReader reader;
  reader.attach(log, "comma2k19_rav4_seg40_candump.log");
  can::Record rec;
  can::Odometry co;
  for (;;) {
    const auto r = reader.next(rec);
    if (r == can::CandumpReader::Result::End || r == can::CandumpReader::Result::IoError) break;
    if (r != can::CandumpReader::Result::Frame || !profile.consume(rec.frame, co)) continue;
    Input in{};
    in.t = co.t;
    in.odo.t = co.t;
    if (co.updated & can::kOdoSpeed) in.odo.flags |= track::kOdoSpeed, in.odo.speed_mps = co.speed_mps;
    if (co.updated & can::kOdoYawRate) in.odo.flags |= track::kOdoYawRate, in.odo.yaw_rate_dps = co.yaw_rate_dps;
    if (co.updated & can::kOdoWheelSpeeds) {
      in.odo.flags |= track::kOdoWheelSpeeds;
      std::memcpy(in.odo.wheel_speeds_mps, co.wheel_speeds_mps, sizeof co.wheel_speeds_mps);
    }
    if (co.gear == can::Gear::Reverse) in.odo.flags |= track::kOdoGear, in.odo.reverse = true;
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
// Map matching on Monaco

struct MatchResult {
  size_t epochs = 0, on_cell = 0, fix_epochs = 0, fix_on_cell = 0, settled = 0, settled_ok = 0;
  size_t warm_epochs = 0, warm_on_cell = 0;    // after the first 10 s of each drive
  size_t inner_epochs = 0, inner_on_cell = 0;  // truth at least 2 m from both ends of its cell
  size_t drives = 0;
  double km = 0;
  uint64_t breaks = 0, steps = 0;
  std::vector<track::MatchObservation> observations;
  std::vector<size_t> drive_starts;
};

track::TrackerDesc g_match_desc;  // --map-aid-sigma, --lane-offset (for experiments)

MatchResult benchMatching(const stream::City& city, double sigma, uint32_t routes, bool with_odometry,
                          const std::string& trace_path = std::string()) {
  MatchResult res;
  FILE* tf = trace_path.empty() ? nullptr : std::fopen(trace_path.c_str(), "w");
  if (tf)
    std::fprintf(tf, "drive,t,fix,true_cell,true_arc,true_len,cell,arc,conf,err_m,sigma_m,true_e,true_n,e,n,heading,true_heading,est_arc_on_true,est_dist_on_true\n");
  const graph::StreetGraph& g = city.graph();
  for (uint32_t r = 0; r < routes; ++r) {
    track::SimDesc sd;
    sd.seed = 1000 + r;
    sd.route_cells = 60;
    sd.gnss_sigma_m = sigma;
    const track::SimTrace trace = track::simulateDrive(g, city.frame(), sd);
    if (trace.epochs.empty()) continue;
    ++res.drives;
    res.km += trace.distance_m / 1000.0;
    std::vector<Input> inputs;
    for (const auto& f : trace.fixes) inputs.push_back(Input{f.t, true, f, {}});
    if (with_odometry)
      for (const auto& o : trace.odometry) inputs.push_back(Input{o.t, false, {}, o});
    sortInputs(inputs);
    track::Tracker tr(city.frame(), &g, g_match_desc);
    res.drive_starts.push_back(res.observations.size());
    uint64_t steps = 0;
    size_t k = 0;
    std::vector<std::pair<double, uint32_t>> truth;  // (t, cell) per epoch, for the settled check
    for (size_t e = 0; e < trace.epochs.size(); ++e) {
      const track::SimSample& s = trace.epochs[e];
      truth.emplace_back(s.t, s.cell);
      for (; k < inputs.size() && inputs[k].t <= s.t; ++k) {
        if (inputs[k].gnss) tr.feedGnss(inputs[k].fix);
        else tr.feedOdometry(inputs[k].odo);
        // Keep the ring from overflowing: update between odometry bursts.
        if (!inputs[k].gnss && k % 64 == 63) tr.update(inputs[k].t);
        if (tr.matcher()->stats().steps != steps) {
          steps = tr.matcher()->stats().steps;
          res.observations.push_back(tr.matcher()->lastObservation());
        }
      }
      const track::Pose& p = tr.update(s.t);
      if (tr.matcher()->stats().steps != steps) {
        steps = tr.matcher()->stats().steps;
        res.observations.push_back(tr.matcher()->lastObservation());
      }
      ++res.epochs;
      const bool ok = p.cell == s.cell;
      if (tf)
        std::fprintf(tf, "%u,%.2f,%d,%u,%.2f,%.2f,%u,%.2f,%.3f,%.2f,%.2f,%.2f,%.2f,%.2f,%.2f,%.1f,%.1f", r, s.t,
                     trace.epoch_has_fix[e], s.cell, s.arc_m, g.halfedges[s.cell].length, p.cell, p.arc_m, p.confidence,
                     std::hypot(p.e - s.e, p.n - s.n), p.pos_sigma_m, s.e, s.n, p.e, p.n, p.heading_deg, s.heading_deg);
      if (tf) {
        const track::CellPoint q = tr.matcher()->project(s.cell, p.e, p.n);
        std::fprintf(tf, ",%.2f,%.2f\n", q.arc_m, q.dist_m);
      }
      res.on_cell += ok;
      if (trace.epoch_has_fix[e]) ++res.fix_epochs, res.fix_on_cell += ok;
      if (s.t > 10.0) ++res.warm_epochs, res.warm_on_cell += ok;
      if (s.arc_m >= 2.0 && g.halfedges[s.cell].length - s.arc_m >= 2.0) ++res.inner_epochs, res.inner_on_cell += ok;
      if (p.settled_cell != track::kNoCell) {
        for (auto it = truth.rbegin(); it != truth.rend(); ++it)
          if (std::fabs(it->first - p.settled_t) < 1e-6) {
            ++res.settled;
            res.settled_ok += it->second == p.settled_cell;
            break;
          }
      }
    }
    res.breaks += tr.stats().match.breaks;
    res.steps += tr.stats().match.steps;
  }
  if (tf) std::fclose(tf);
  return res;
}

// Replays recorded observations through fresh matchers, timing each step.
double timeSteps(const graph::StreetGraph& g, const std::vector<MatchResult*>& runs, int repeats) {
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

}  // namespace

int main(int argc, char** argv) {
  std::string package, data;
  uint32_t routes = 50;
  bool check = false, timing_check = true;
  // The targets; --min-on-cell5/15 lower them (CTest track.bench uses
  // regression floors, see tests/track/CMakeLists.txt).
  double min_on5 = 0.99, min_on15 = 0.95;
  double latency = 0;
  std::string trace;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--package" && i + 1 < argc) package = argv[++i];
    else if (a == "--data" && i + 1 < argc) data = argv[++i];
    else if (a == "--routes" && i + 1 < argc) routes = static_cast<uint32_t>(std::stoul(argv[++i]));
    else if (a == "--gnss-latency" && i + 1 < argc) latency = std::stod(argv[++i]);
    else if (a == "--trace" && i + 1 < argc) trace = argv[++i];
    else if (a == "--map-aid-sigma" && i + 1 < argc) g_match_desc.map_aid_sigma_m = std::stod(argv[++i]);
    else if (a == "--map-aid-confidence" && i + 1 < argc) g_match_desc.map_aid_min_confidence = std::stod(argv[++i]);
    else if (a == "--ambiguity" && i + 1 < argc) g_match_desc.ambiguity_sigmas = std::stod(argv[++i]);
    else if (a == "--lane-offset" && i + 1 < argc) g_match_desc.lane_offset_m = std::stod(argv[++i]);
    else if (a == "--check") check = true;
    else if (a == "--min-on-cell5" && i + 1 < argc) min_on5 = std::stod(argv[++i]);
    else if (a == "--min-on-cell15" && i + 1 < argc) min_on15 = std::stod(argv[++i]);
    else if (a == "--no-timing-check") timing_check = false;
    else {
      std::fprintf(stderr,
                   "usage: %s --package PKG --data TESTS_DATA_DIR [--routes N] [--gnss-latency S] [--trace PREFIX] [--check] "
                   "[--min-on-cell5 X] [--min-on-cell15 X] [--no-timing-check] [--map-aid-sigma S] "
                   "[--map-aid-confidence C] [--lane-offset M] [--ambiguity K]\n",
                   argv[0]);
      return 2;
    }
  }
  if (package.empty() || data.empty()) {
    std::fprintf(stderr, "%s: --package and --data are required\n", argv[0]);
    return 2;
  }
  try {
    const FusionResult fu = benchFusion(data, latency, trace);

    stream::City city;
    std::string err;
    if (city.open(package, err) != core::Status::Ok) throw std::runtime_error(err);
    MatchResult m5 = benchMatching(city, 5, routes, true, trace.empty() ? "" : trace + "-match5.csv");
    MatchResult m15 = benchMatching(city, 15, routes, true, trace.empty() ? "" : trace + "-match15.csv");
    const MatchResult g5 = benchMatching(city, 5, routes, false);
    const MatchResult g15 = benchMatching(city, 15, routes, false);
    const double us = timeSteps(city.graph(), {&m5, &m15}, 3);
    const track::MapMatcher probe(city.graph());

    auto share = [](size_t a, size_t b) { return b ? static_cast<double>(a) / static_cast<double>(b) : NAN; };
    const double on5 = share(m5.on_cell, m5.epochs), on15 = share(m15.on_cell, m15.epochs);
    std::printf("{\n");
    std::printf("  \"on_cell_sigma5\": %.4f,\n  \"on_cell_sigma15\": %.4f,\n", on5, on15);
    std::printf("  \"update_us_p50\": %.2f,\n", us);
    std::printf("  \"fusion_err_m_p50\": %.3f,\n  \"dr_drift_pct\": %.3f,\n", fu.err_p50, fu.drift_pct);
    std::printf("  \"targets\": {\"on_cell_sigma5\": {\"min\": 0.99, \"met\": %s}, "
                "\"on_cell_sigma15\": {\"min\": 0.95, \"met\": %s}, \"update_us_p50\": {\"max\": 20, \"met\": %s}, "
                "\"fusion_err_m_p50\": {\"max\": 1.5, \"met\": %s}, \"dr_drift_pct\": {\"max\": 2, \"met\": %s}},\n",
                on5 >= 0.99 ? "true" : "false", on15 >= 0.95 ? "true" : "false", us <= 20 ? "true" : "false",
                fu.err_p50 <= 1.5 ? "true" : "false", fu.drift_pct <= 2 ? "true" : "false");
    std::printf("  \"detail\": {\n");
    std::printf("    \"fusion_err_m_p95\": %.3f, \"gnss_raw_err_m_p50\": %.3f, \"fusion_poses\": %zu,\n", fu.err_p95,
                fu.raw_gnss_p50, fu.poses);
    std::printf("    \"fusion_gnss_fixes\": %zu, \"fusion_odometry_samples\": %zu, \"fusion_gnss_rejected\": %llu,\n",
                fu.gnss, fu.odometry, static_cast<unsigned long long>(fu.rejected));
    std::printf("    \"dr_err_end_m\": %.3f, \"dr_err_max_m\": %.3f, \"dr_distance_m\": %.1f, \"gnss_latency_s\": %.3f,\n",
                fu.drift_err_m, fu.drift_max_err_m, fu.drift_dist_m, latency);
    auto printMatch = [&](const char* name, const MatchResult& r, bool last) {
      std::printf("    \"%s\": {\"drives\": %zu, \"km\": %.2f, \"epochs\": %zu, \"on_cell\": %.4f, "
                  "\"on_cell_fix_epochs\": %.4f, \"on_cell_after_10s\": %.4f, \"on_cell_2m_from_junctions\": %.4f, "
                  "\"settled_on_cell\": %.4f, \"hmm_steps\": %llu, \"hmm_breaks\": %llu}%s\n",
                  name, r.drives, r.km, r.epochs, share(r.on_cell, r.epochs), share(r.fix_on_cell, r.fix_epochs),
                  share(r.warm_on_cell, r.warm_epochs), share(r.inner_on_cell, r.inner_epochs),
                  share(r.settled_ok, r.settled), static_cast<unsigned long long>(r.steps),
                  static_cast<unsigned long long>(r.breaks), last ? "" : ",");
    };
    printMatch("match_sigma5", m5, false);
    printMatch("match_sigma15", m15, false);
    printMatch("match_sigma5_gnss_only", g5, false);
    printMatch("match_sigma15_gnss_only", g15, false);
    std::printf("    \"graph_cells\": %zu, \"index_entries\": %zu, \"matcher_bytes\": %zu\n", city.graph().cellCount(),
                probe.grid().entryCount(), probe.bytes());
    std::printf("  }\n}\n");

    if (check) {
      bool ok = true;
      auto expect = [&](bool cond, const char* what, double value) {
        if (!cond) {
          std::fprintf(stderr, "FAIL: %s (measured %.4f)\n", what, value);
          ok = false;
        }
      };
      char what5[64], what15[64];
      std::snprintf(what5, sizeof what5, "on_cell_sigma5 >= %.3f", min_on5);
      std::snprintf(what15, sizeof what15, "on_cell_sigma15 >= %.3f", min_on15);
      expect(on5 >= min_on5, what5, on5);
      expect(on15 >= min_on15, what15, on15);
      expect(fu.err_p50 <= 1.5, "fusion_err_m_p50 <= 1.5", fu.err_p50);
      expect(fu.drift_pct <= 2.0, "dr_drift_pct <= 2", fu.drift_pct);
      if (timing_check) expect(us <= 20.0, "update_us_p50 <= 20", us);
      return ok ? 0 : 1;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_track: %s\n", e.what());
    return 1;
  }
  return 0;
}
