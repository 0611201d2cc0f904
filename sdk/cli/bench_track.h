// The tracking benchmark, shared by `blvd bench track` (cmd_bench_track.cpp)
// and its CTests (which run the CLI):
//
//   fusion_err_m_p50   comma2k19 RAV4 minute: u-blox fixes (stamped on arrival, no
//                      accuracy in the log) + CAN speed and yaw rate (the candump through
//                      the Toyota profile) fused by the EKF; median distance to comma's
//                      reference pose at its 20 Hz frame times. Target <= 1.5 m.
//   dr_drift_pct       the same with the GNSS of the last 30 s withheld: position error
//                      at the end / distance driven in those 30 s. Target <= 2 %.
//   on_cell_sigma5     Monaco: seeded drives by adapters/sim (routes of 60 cells), written
//   on_cell_sigma15    as NMEA text (RMC+GGA+GST at 1 Hz, noise sigma 5 m / 15 m per axis,
//                      10 % of the fixes dropped, one 20 s outage) and Toyota-DBC CAN frames
//                      in candump format (50 Hz), parsed back by the gnss and can adapters
//                      (adapters/replay) and tracked; the share of 1 Hz epochs (dropped,
//                      outage and first epochs included) whose pose is on the true cell.
//                      Targets >= 0.99 / >= 0.95.
//   on_cell_sigma5_calibrated / on_cell_sigma15_calibrated
//                      the same drives, each after the first starting from the odometry
//                      calibration the previous one ended with (not target keys).
//   on_cell_sigma5_chained / _resumed, on_cell_sigma15_chained / _resumed
//                      the seeded drives chained: each parks halfway along its last cell and
//                      the next pulls away from there (towed to its seeded street when no
//                      route of half the cells goes on), tracked cold and resumed from the
//                      previous drive's last pose (Tracker::setStartPose) and calibration.
//                      --check requires resumed > chained (not target keys).
//   update_us_p50      median wall time of one map-matching step (MapMatcher::step),
//                      replaying the drives' observations (steady_clock per step, 3 passes).
//                      Target <= 20 us (tests/bench/bench_tracker.cpp measures the same
//                      with Google Benchmark).
//
// --trace PREFIX writes one CSV row per pose of the matching runs (PREFIX-match5.csv,
// PREFIX-match15.csv, and -calibrated, -chained, -resumed of each; PREFIX-gnss5.csv and
// -gnss15.csv without odometry): the truth, the pose and the filter's state (columns in the header),
// for classifying the misses; --match-only / --match5-only run just the on-cell parts.
#pragma once

#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "track/tracker.h"

namespace blvd::cli {

struct TrackBenchOptions {
  std::string package;    // a .blvd; empty: the bundled Monaco extract, baked once into a cache file
  std::string data_dir;   // tests/data (comma2k19 logs, DBCs); empty: found from the working directory
  std::string osm;        // the OSM extract baked when `package` is empty; empty: data/osm/monaco-geofabrik-2026.osm.pbf
  uint32_t routes = 50;
  uint32_t route_cells = 60;
  double sigma_low = 5, sigma_high = 15;  // GNSS noise of the two matching runs (the keys say 5 and 15)
  double gnss_latency_s = 0;
  std::string trace_prefix;  // writes per-pose CSVs PREFIX.csv, PREFIX-dr.csv, PREFIX-match5.csv, ...
  track::TrackerDesc tracker;  // for the matching runs (experiments: map aid, lane offset, ...)
  bool quiet = false;          // no progress on stderr
  // Experiments: only the on-cell runs with odometry (sigma_low, and sigma_high unless
  // match_low_only); no fusion, no GNSS-only runs, no timing (those keys are NaN).
  bool match_only = false, match_low_only = false;
  // Experiments on the simulated drives, for bounds rather than figures: the car's
  // lane wander (SimDesc::lane_wander_m; negative: the simulator's default), and
  // every drive's filter started from the simulator's true wheel-speed scale and
  // yaw-rate bias (sigmas at the floors of Ekf::setCalibration).
  double sim_lane_wander_m = -1;
  bool oracle_calibration = false;
};

// Runs everything; throws core::Error naming the file on bad input. The JSON holds
// the five keys, "targets" (each with its bound and whether it is met) and "detail".
nlohmann::json runTrackBench(const TrackBenchOptions& opt);

// The package the bench uses when none is given: bakes `osm` (street graph and
// blocks, no impostors) to a file in the temporary directory unless a bake of the
// same source is already there. Returns its path.
std::string benchPackage(const std::string& osm, bool quiet);

}  // namespace blvd::cli
