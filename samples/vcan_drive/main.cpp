// vcan_drive: CAN bus in, tracked poses (and headless frames) out.
//
//   vcan0 / candump log -> CanInput -> CanFeed -> Tracking: the C API runtime
//     (blvd_feed_can_frame), or sdk/track without GL (the decoded blvd_odometry)
//     -> poses.jsonl, frames/*.png, stats.json
//
// Built twice from these sources (see CMakeLists.txt): `vcan_drive`, the full
// sample on the C API, and `vcan_drive_track`, the same program without GL for
// a track-only host (no libblvd, no Mesa: it fits a small qemu guest).
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "calibration.h"
#include "can_feed.h"
#include "can_input.h"
#include "gnss_feed.h"
#include "common/backend.h"
#include "common/data_dir.h"
#include "common/logs.h"
#include "common/memory.h"
#include "tracking.h"
#if VCAN_DRIVE_CAPI
#include "frames.h"
#endif

namespace {

using namespace vcan_drive;
using namespace samples;  // common/: backend.h, logs.h, memory.h
using Clock = std::chrono::steady_clock;

volatile std::sig_atomic_t g_stop = 0;  // SIGINT/SIGTERM
void onSignal(int) { g_stop = 1; }

struct Options {
  std::string iface = "vcan0";
  std::string candump;
  std::string dbc = blvd::samples::defaultDbc("toyota_new_mc_pt_generated.dbc");  // common/data_dir.h
  std::string vehicle = "toyota";
  std::string package;
  bool no_render = false;
  bool display = false;
  std::string backend = "auto";
  uint32_t width = 800, height = 480;
  std::string frames_dir;
  unsigned render_every = 10;
  std::string poses_path, odometry_path, stats_path, render_poses;
  double pose_interval_s = 0.1;
  std::vector<double> start;  // lat, lon[, heading]
  std::string nmea;
  double nmea_offset_s = 0;
  double trace_t0 = 0;
  bool has_trace_t0 = false;
  double idle_exit_s = 0, duration_s = 0;
  std::string ready_file;
  int rcvbuf = 4 << 20;
  std::string calibration;  // odometry calibration kept between drives (calibration.h)
};

// A start pose at time t (blvd_set_start_pose): --start's LAT LON HEADING, with
// the 5 m of a first fix, or the pose the last drive ended with.
blvd_start_pose startPose(const std::vector<double>& start, double t) {
  blvd_start_pose sp{};
  sp.struct_size = sizeof sp;
  sp.t = t;
  sp.lat = start[0];
  sp.lon = start[1];
  sp.heading_deg = start[2];
  sp.sigma_m = 5;
  return sp;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  CLI::App app{"vcan_drive: tracks a vehicle from its CAN bus with blvd (see samples/vcan_drive/README.md)"};
  app.add_option("--iface", opt.iface, "SocketCAN interface")->capture_default_str();
  app.add_option("--candump", opt.candump, "read a candump -l log instead of an interface");
  app.add_option("--dbc", opt.dbc, "DBC file")->capture_default_str();
  app.add_option("--vehicle", opt.vehicle, "toyota, vw_mqb or hyundai")->capture_default_str();
  app.add_option("--start", opt.start, "LAT LON HEADING: where dead reckoning starts without GNSS (blvd_set_start_pose)")
      ->expected(3);
  app.add_option("--nmea", opt.nmea, "GNSS fixes from an NMEA log on the CAN trace's clock, fed in step with the bus");
  app.add_option("--nmea-offset", opt.nmea_offset_s, "seconds added to the NMEA times to put them on the trace clock");
  CLI::Option* t0_opt =
      app.add_option("--trace-t0", opt.trace_t0, "on a live bus: the trace time of the first frame (default: first fix)");
  app.add_option("--poses", opt.poses_path, "write poses as JSON lines");
  app.add_option("--odometry", opt.odometry_path, "write the decoded odometry as JSON lines");
  app.add_option("--stats", opt.stats_path, "write the run's stats JSON");
  app.add_option("--calibration", opt.calibration,
                 "odometry calibration and last pose kept between drives: read at start (when the file exists), "
                 "written at exit");
  app.add_option("--pose-interval", opt.pose_interval_s, "seconds of bus time between poses")->capture_default_str();
  app.add_option("--idle-exit", opt.idle_exit_s, "stop after this many seconds without a frame (0: never)");
  app.add_option("--duration", opt.duration_s, "stop after this many seconds (0: never)");
  app.add_option("--ready-file", opt.ready_file, "create this file once the interface is open");
  app.add_option("--rcvbuf", opt.rcvbuf, "socket receive buffer, bytes")->capture_default_str();
#if VCAN_DRIVE_CAPI
  app.add_option("--package", opt.package, "a .blvd package: map matching, and frames");
  app.add_flag("--no-render", opt.no_render, "track only; no GL");
  app.add_flag("--display", opt.display, "show the frames in a window (X11)");
  app.add_option("--backend", opt.backend, "auto, surfaceless, device or osmesa")->capture_default_str();
  app.add_option("--width", opt.width)->capture_default_str();
  app.add_option("--height", opt.height)->capture_default_str();
  app.add_option("--frames", opt.frames_dir, "write every N-th frame as PNG into this folder");
  app.add_option("--render-every", opt.render_every, "render every N-th pose")->capture_default_str()->check(
      CLI::PositiveNumber);
  app.add_option("--render-poses", opt.render_poses, "render a poses JSONL recorded by vcan_drive_track; no CAN");
#else
  app.add_option("--package", opt.package, "a .blvd package: map matching (this build never renders)");
  opt.no_render = true;
#endif
  CLI11_PARSE(app, argc, argv);
  opt.has_trace_t0 = t0_opt->count() > 0;

  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  const auto wall0 = Clock::now();
  std::string err;

  GnssFeed gnss;
  if (!opt.nmea.empty() && gnss.open(opt.nmea, opt.nmea_offset_s, err) != BLVD_OK) {
    std::fprintf(stderr, "vcan_drive: %s\n", err.c_str());
    return 2;
  }

  blvd::vehicle::Vehicle vehicle;
  if (!blvd::vehicle::parseVehicle(opt.vehicle, vehicle)) {
    std::fprintf(stderr, "vcan_drive: unknown vehicle %s\n", opt.vehicle.c_str());
    return 2;
  }
  TrackingDesc td;
  td.package = opt.package;
  td.dbc_path = opt.dbc;
  td.vehicle = static_cast<blvd_vehicle>(vehicle);  // the same enumeration (sdk/capi/capi_vehicle.cpp checks)
  td.width = opt.width;
  td.height = opt.height;
  td.backend = parseBackend(opt.backend);
  // Without a package the local frame sits at the start, else at the first fix.
  blvd_gnss_fix first_fix{};
  if (!opt.start.empty())
    td.origin_lat = opt.start[0], td.origin_lon = opt.start[1];
  else if (gnss.isOpen() && gnss.first(first_fix))
    td.origin_lat = first_fix.lat, td.origin_lon = first_fix.lon;

  std::unique_ptr<Tracking> tracking;
#if VCAN_DRIVE_CAPI
  const bool want_render = !opt.no_render || !opt.render_poses.empty();
  if (!opt.package.empty() && want_render) {
    tracking = makeCapiTracking(td, err);
    if (!tracking) {
      std::fprintf(stderr, "vcan_drive: %s\n", err.c_str());
      return 2;
    }
  }
  Frames frames;
  if (tracking) {
    if (!frames.open(*tracking, opt.frames_dir, opt.display, err)) {
      std::fprintf(stderr, "vcan_drive: %s\n", err.c_str());
      return 2;
    }
  } else if (opt.display || !opt.frames_dir.empty()) {
    std::fprintf(stderr, "vcan_drive: --display and --frames need --package and rendering\n");
    return 2;
  }
  if (!opt.render_poses.empty()) {
    if (!tracking) {
      std::fprintf(stderr, "vcan_drive: --render-poses needs --package\n");
      return 2;
    }
    return renderRecorded(opt.render_poses, opt.render_every, opt.stats_path, frames, g_stop);
  }
#endif
  if (!tracking) {
    // Track only: the C API cannot track without GL (see tracking.h).
    tracking = makeDirectTracking(td, err);
    if (!tracking) {
      std::fprintf(stderr, "vcan_drive: %s\n", err.c_str());
      return 2;
    }
  }
  if (opt.package.empty() && opt.start.empty() && opt.nmea.empty())
    std::fprintf(stderr, "vcan_drive: no --start and no --nmea: odometry is decoded, but poses stay invalid\n");
  // The calibration the last drive learnt, before the first fix (none yet on a first drive),
  // and the pose it ended with (used at the first frame unless --start says otherwise).
  bool calibration_loaded = false;
  KeyOffState stored;
  if (!opt.calibration.empty()) {
    const CalibrationRead cr = readCalibration(opt.calibration, stored, err);
    if (cr == CalibrationRead::Bad) {
      std::fprintf(stderr, "vcan_drive: %s\n", err.c_str());
      return 2;
    }
    if (cr == CalibrationRead::Loaded) {
      if (tracking->setCalibration(stored.calibration) != BLVD_OK) {
        std::fprintf(stderr, "vcan_drive: %s: %s\n", opt.calibration.c_str(), tracking->lastError().c_str());
        return 2;
      }
      calibration_loaded = true;
    }
  }
  // Where tracking starts at the first frame: --start, else the stored pose, else the first fix.
  const bool resume_pose = stored.has_pose && opt.start.empty();
  const bool has_start = resume_pose || !opt.start.empty();
  blvd_start_pose start = resume_pose ? stored.pose : blvd_start_pose{};
  if (!opt.start.empty()) start = startPose(opt.start, 0);
  const std::string start_source = resume_pose ? opt.calibration : "--start";

  CanFeed feed;
  if (feed.open(opt.dbc, vehicle, err) != BLVD_OK) {
    std::fprintf(stderr, "vcan_drive: %s\n", err.c_str());
    return 2;
  }
  CanInput input;
  CanInputDesc cd;
  cd.iface = opt.iface;
  cd.candump = opt.candump;
  cd.ids = feed.messageIds();
  cd.rcvbuf_bytes = opt.rcvbuf;
  if (input.open(cd, err) != BLVD_OK) {
    std::fprintf(stderr, "vcan_drive: %s\n", err.c_str());
    return 2;
  }
  if (!opt.ready_file.empty()) std::ofstream(opt.ready_file) << input.describe() << "\n";

  JsonLines poses, odolog;
  if (!poses.open(opt.poses_path, err) || !odolog.open(opt.odometry_path, err)) {
    std::fprintf(stderr, "vcan_drive: %s\n", err.c_str());
    return 2;
  }

  uint64_t pose_count = 0, valid = 0, matched = 0, bad_lines = 0;
  std::vector<uint32_t> cells;
  double first_t = 0, last_t = 0, next_pose_t = 0;
  double to_rx = 0;  // receiving clock - trace clock
  bool started = false;
  auto last_frame_wall = Clock::now();
  int rc = 0;
  blvd::can::Frame f;
  blvd_odometry odo{};
  while (!g_stop) {
#if VCAN_DRIVE_CAPI
    if (frames.closed()) break;  // --display window closed
#endif
    const auto now = Clock::now();
    if (opt.duration_s > 0 && std::chrono::duration<double>(now - wall0).count() >= opt.duration_s) break;
    if (opt.idle_exit_s > 0 && started &&
        std::chrono::duration<double>(now - last_frame_wall).count() >= opt.idle_exit_s)
      break;
    const CanInput::Result res = input.next(f, 200, err);
    if (res == CanInput::Result::End) break;
    if (res == CanInput::Result::Timeout) continue;
    if (res == CanInput::Result::BadLine) {
      ++bad_lines;
      std::fprintf(stderr, "vcan_drive: %s\n", err.c_str());
      continue;
    }
    if (res == CanInput::Result::Error) {
      std::fprintf(stderr, "vcan_drive: %s: %s\n", input.describe().c_str(), err.c_str());
      rc = 1;
      break;
    }
    last_frame_wall = Clock::now();
    if (!started) {
      started = true;
      first_t = f.t;
      next_pose_t = f.t;
      start.t = f.t;
      if (has_start && tracking->setStartPose(start) != BLVD_OK) {
        std::fprintf(stderr, "vcan_drive: %s: %s\n", start_source.c_str(), tracking->lastError().c_str());
        rc = 2;  // the stored state is left as it was
        break;
      }
      // A candump file is its own trace clock; a live bus is placed on it at its first frame.
      double t0 = f.t;  // this frame's time on the trace clock
      if (opt.candump.empty() && opt.has_trace_t0)
        t0 = opt.trace_t0;
      else if (opt.candump.empty() && gnss.isOpen() && gnss.first(first_fix))
        t0 = first_fix.t;
      to_rx = f.t - t0;
    }
    last_t = f.t;
    if (gnss.isOpen()) gnss.feedUntil(f.t - to_rx, to_rx, *tracking);
    if (feed.feed(f, *tracking, odo)) odolog.odometry(odo, f.id);
    if (f.t < next_pose_t) continue;
    next_pose_t = f.t + opt.pose_interval_s;
    blvd_pose p{};
    if (tracking->getPose(f.t, p) != BLVD_OK) {
      std::fprintf(stderr, "vcan_drive: blvd_get_pose: %s\n", tracking->lastError().c_str());
      rc = 1;
      break;
    }
    poses.pose(p);
    ++pose_count;
    if (p.flags & BLVD_POSE_VALID) ++valid;
    if (p.flags & BLVD_POSE_MATCHED) ++matched;
    noteCell(cells, p);
#if VCAN_DRIVE_CAPI
    if (tracking->canRender() && !opt.no_render && (pose_count - 1) % opt.render_every == 0 && !frames.frame(nullptr)) {
      rc = 1;
      break;
    }
#endif
  }

  if (!poses.close(err) || !odolog.close(err)) {
    std::fprintf(stderr, "vcan_drive: %s\n", err.c_str());
    rc = 1;
  }
  // What this drive learnt and where it ended, for the next one (key-off).
  KeyOffState end;
  blvd_odometry_calibration& cal_end = end.calibration;
  blvd_pose last_pose{};
  if (started && tracking->getPose(last_t, last_pose) == BLVD_OK &&
      (last_pose.flags & (BLVD_POSE_VALID | BLVD_POSE_HEADING_VALID)) == (BLVD_POSE_VALID | BLVD_POSE_HEADING_VALID)) {
    end.has_pose = true;
    end.pose.struct_size = sizeof end.pose;
    end.pose.lat = last_pose.lat;
    end.pose.lon = last_pose.lon;
    end.pose.heading_deg = last_pose.heading_deg;
    end.pose.sigma_m = last_pose.pos_sigma_m;
    end.pose.heading_sigma_deg = last_pose.heading_sigma_deg;
  }
  if (tracking->getCalibration(cal_end) != BLVD_OK) {
    std::fprintf(stderr, "vcan_drive: blvd_get_odometry_calibration: %s\n", tracking->lastError().c_str());
    rc = 1;
  } else if (!opt.calibration.empty() && rc != 2 && !writeCalibration(opt.calibration, end, err)) {
    std::fprintf(stderr, "vcan_drive: %s\n", err.c_str());
    rc = 1;
  }
  const CanFeedStats& fs = feed.stats();
  nlohmann::json j;
  j["input"] = input.describe();
  j["tracking"] = tracking->name();
  j["package"] = opt.package;
  j["frames"] = fs.frames;
  j["mapped_frames"] = fs.mapped;
  j["can_feed"] = tracking->feedsCanFrames() ? "blvd_feed_can_frame" : "decoded";
  j["can_frames_fed"] = fs.can_frames_fed;
  j["odometry_fed"] = fs.odometry_fed;
  j["feed_errors"] = fs.feed_errors;
  j["kernel_dropped"] = input.kernelDropped();
  j["error_frames"] = input.errorFrames();
  j["bus_off"] = input.busOffs();
  j["bad_lines"] = bad_lines;
  j["gnss_fed"] = gnss.fed();
  j["gnss_untimed"] = gnss.untimed();
  j["nmea_diagnostics"] = gnss.diagnostics();
  j["first_t"] = first_t;
  j["last_t"] = last_t;
  j["poses"] = pose_count;
  j["valid_poses"] = valid;
  j["matched_poses"] = matched;
  j["cells_visited"] = cells;
  j["calibration"] = {{"file", opt.calibration},
                      {"loaded", calibration_loaded},
                      {"start_pose_loaded", resume_pose},
                      {"start_pose_written", end.has_pose},
                      {"speed_scale", cal_end.speed_scale},
                      {"speed_scale_sigma", cal_end.speed_scale_sigma},
                      {"yaw_rate_bias_dps", cal_end.yaw_rate_bias_dps},
                      {"yaw_rate_bias_sigma_dps", cal_end.yaw_rate_bias_sigma_dps}};
  j["wall_s"] = std::chrono::duration<double>(Clock::now() - wall0).count();
  blvd_stats rs{};
  addMemoryStats(j, tracking->runtimeStats(rs) ? &rs : nullptr);
#if VCAN_DRIVE_CAPI
  addRenderStats(j, frames.stats());
#else
  addRenderStats(j, RenderStats{});
#endif
  if (!writeStats(opt.stats_path, j)) {
    std::fprintf(stderr, "vcan_drive: cannot write %s\n", opt.stats_path.c_str());
    rc = 1;
  }
  std::fprintf(stderr, "vcan_drive: %llu frames, %llu odometry samples, %llu poses (%llu valid, %llu matched) from %s\n",
               static_cast<unsigned long long>(fs.frames), static_cast<unsigned long long>(fs.odometry_fed),
               static_cast<unsigned long long>(pose_count), static_cast<unsigned long long>(valid),
               static_cast<unsigned long long>(matched), input.describe().c_str());
  return rc;
}
