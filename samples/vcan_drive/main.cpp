// vcan_drive: CAN bus in, tracked poses (and headless frames) out.
//
//   vcan0 / candump log -> CanInput -> CanFeed -> Tracking: a C API runtime
//     (blvd_feed_can_frame), or a blvd_tracker without GL (the decoded blvd_odometry)
//     -> poses.jsonl, frames/*.png, stats.json
//
// Built twice from these sources (see CMakeLists.txt): `vcan_drive`, the full
// sample, and `vcan_drive_track`, the same program without rendering for a
// track-only host (libblvd opens no GL library: it fits a small qemu guest).
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

// The command line into `opt`; `t0_opt` is --trace-t0 (was it given?).
void addOptions(CLI::App& app, Options& opt, CLI::Option*& t0_opt) {
  app.add_option("--iface", opt.iface, "SocketCAN interface")->capture_default_str();
  app.add_option("--candump", opt.candump, "read a candump -l log instead of an interface");
  app.add_option("--dbc", opt.dbc, "DBC file")->capture_default_str();
  app.add_option("--vehicle", opt.vehicle, "toyota, vw_mqb or hyundai")->capture_default_str();
  app.add_option("--start", opt.start, "LAT LON HEADING: where dead reckoning starts without GNSS (blvd_set_start_pose)")
      ->expected(3);
  app.add_option("--nmea", opt.nmea, "GNSS fixes from an NMEA log on the CAN trace's clock, fed in step with the bus");
  app.add_option("--nmea-offset", opt.nmea_offset_s, "seconds added to the NMEA times to put them on the trace clock");
  t0_opt = app.add_option("--trace-t0", opt.trace_t0, "on a live bus: the trace time of the first frame (default: first fix)");
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
}

// What the tracker is made from. Without a package the local frame sits at
// the start, else at the first fix (`first_fix`, when there is one).
TrackingDesc trackingDesc(const Options& opt, blvd_vehicle vehicle, GnssFeed& gnss, blvd_gnss_fix& first_fix) {
  TrackingDesc td;
  td.package = opt.package;
  td.dbc_path = opt.dbc;
  td.vehicle = vehicle;
  td.width = opt.width;
  td.height = opt.height;
  td.backend = parseBackend(opt.backend);
  if (!opt.start.empty())
    td.origin_lat = opt.start[0], td.origin_lon = opt.start[1];
  else if (gnss.isOpen() && gnss.first(first_fix))
    td.origin_lat = first_fix.lat, td.origin_lon = first_fix.lon;
  return td;
}

// The key-off state of the last drive: its calibration, set before the first
// fix (none yet on a first drive), and the pose it ended with. 0, or 2 with
// the reason printed.
int loadKeyOff(const Options& opt, Tracking& tracking, KeyOffState& stored, bool& calibration_loaded) {
  calibration_loaded = false;
  if (opt.calibration.empty()) return 0;
  std::string err;
  const CalibrationRead cr = readCalibration(opt.calibration, stored, err);
  if (cr == CalibrationRead::Bad) {
    std::fprintf(stderr, "vcan_drive: %s\n", err.c_str());
    return 2;
  }
  if (cr != CalibrationRead::Loaded) return 0;
  if (tracking.setCalibration(stored.calibration) != BLVD_OK) {
    std::fprintf(stderr, "vcan_drive: %s: %s\n", opt.calibration.c_str(), tracking.lastError().c_str());
    return 2;
  }
  calibration_loaded = true;
  return 0;
}

// Where tracking starts at the first frame: --start, else the stored pose, else the first fix.
struct Start {
  bool has = false, resumed = false;
  blvd_start_pose pose{};
  std::string source;
};
Start startFrom(const Options& opt, const KeyOffState& stored) {
  Start s;
  s.resumed = stored.has_pose && opt.start.empty();
  s.has = s.resumed || !opt.start.empty();
  if (s.resumed) s.pose = stored.pose;
  if (!opt.start.empty()) s.pose = startPose(opt.start, 0);
  s.source = s.resumed ? opt.calibration : "--start";
  return s;
}

// What the drive reads and writes.
struct DriveIo {
  GnssFeed& gnss;
  CanFeed& feed;
  CanInput& input;
  JsonLines& poses;
  JsonLines& odolog;
#if VCAN_DRIVE_CAPI
  Frames* frames = nullptr;
#endif
};

// What the drive counted.
struct Drive {
  uint64_t pose_count = 0, valid = 0, matched = 0, bad_lines = 0;
  std::vector<uint32_t> cells;
  double first_t = 0, last_t = 0;
  double to_rx = 0;  // receiving clock - trace clock
  double next_pose_t = 0;
  bool started = false;
};

// The first frame: tracking starts (at `start` when there is one) and a live
// bus is placed on the trace clock. 0, or 2 when the start pose is refused.
int firstFrame(const Options& opt, const blvd::can::Frame& f, DriveIo& io, Tracking& tracking, Start& start, Drive& d) {
  d.started = true;
  d.first_t = d.next_pose_t = f.t;
  start.pose.t = f.t;
  if (start.has && tracking.setStartPose(start.pose) != BLVD_OK) {
    std::fprintf(stderr, "vcan_drive: %s: %s\n", start.source.c_str(), tracking.lastError().c_str());
    return 2;  // the stored state is left as it was
  }
  // A candump file is its own trace clock; a live bus is placed on it at its first frame.
  double t0 = f.t;  // this frame's time on the trace clock
  blvd_gnss_fix first_fix{};
  if (opt.candump.empty() && opt.has_trace_t0)
    t0 = opt.trace_t0;
  else if (opt.candump.empty() && io.gnss.isOpen() && io.gnss.first(first_fix))
    t0 = first_fix.t;
  d.to_rx = f.t - t0;
  return 0;
}

// One frame: GNSS up to it, the frame itself, and a pose (and frame) every
// pose_interval_s of bus time. 0, or 1 on a tracking or rendering failure.
int onFrame(const Options& opt, const blvd::can::Frame& f, DriveIo& io, Tracking& tracking, Drive& d) {
  d.last_t = f.t;
  if (io.gnss.isOpen()) io.gnss.feedUntil(f.t - d.to_rx, d.to_rx, tracking);
  blvd_odometry odo{};
  if (io.feed.feed(f, tracking, odo)) io.odolog.odometry(odo, f.id);
  if (f.t < d.next_pose_t) return 0;
  d.next_pose_t = f.t + opt.pose_interval_s;
  blvd_pose p{};
  if (tracking.getPose(f.t, p) != BLVD_OK) {
    std::fprintf(stderr, "vcan_drive: blvd_get_pose: %s\n", tracking.lastError().c_str());
    return 1;
  }
  io.poses.pose(p);
  ++d.pose_count;
  if (p.flags & BLVD_POSE_VALID) ++d.valid;
  if (p.flags & BLVD_POSE_MATCHED) ++d.matched;
  noteCell(d.cells, p);
#if VCAN_DRIVE_CAPI
  if (tracking.canRender() && !opt.no_render && (d.pose_count - 1) % opt.render_every == 0 && !io.frames->frame(nullptr))
    return 1;
#endif
  return 0;
}

// Frames until the input ends, a stop condition holds or something fails.
int runDrive(const Options& opt, DriveIo& io, Tracking& tracking, Start& start, Drive& d, Clock::time_point wall0) {
  auto last_frame_wall = Clock::now();
  blvd::can::Frame f;
  std::string err;
  while (!g_stop) {
#if VCAN_DRIVE_CAPI
    if (io.frames->closed()) break;  // --display window closed
#endif
    const auto now = Clock::now();
    if (opt.duration_s > 0 && std::chrono::duration<double>(now - wall0).count() >= opt.duration_s) break;
    if (opt.idle_exit_s > 0 && d.started &&
        std::chrono::duration<double>(now - last_frame_wall).count() >= opt.idle_exit_s)
      break;
    const CanInput::Result res = io.input.next(f, 200, err);
    if (res == CanInput::Result::End) break;
    if (res == CanInput::Result::Timeout) continue;
    if (res == CanInput::Result::BadLine) {
      ++d.bad_lines;
      std::fprintf(stderr, "vcan_drive: %s\n", err.c_str());
      continue;
    }
    if (res == CanInput::Result::Error) {
      std::fprintf(stderr, "vcan_drive: %s: %s\n", io.input.describe().c_str(), err.c_str());
      return 1;
    }
    last_frame_wall = Clock::now();
    if (!d.started)
      if (const int rc = firstFrame(opt, f, io, tracking, start, d)) return rc;
    if (const int rc = onFrame(opt, f, io, tracking, d)) return rc;
  }
  return 0;
}

// What this drive learnt and where it ended, for the next one (key-off):
// written to --calibration unless the start failed (rc 2). Returns rc, or 1
// when it cannot be read or written.
int saveKeyOff(const Options& opt, Tracking& tracking, const Drive& d, KeyOffState& end, int rc) {
  blvd_pose last{};
  const uint32_t both = BLVD_POSE_VALID | BLVD_POSE_HEADING_VALID;
  if (d.started && tracking.getPose(d.last_t, last) == BLVD_OK && (last.flags & both) == both) {
    end.has_pose = true;
    end.pose.struct_size = sizeof end.pose;
    end.pose.lat = last.lat;
    end.pose.lon = last.lon;
    end.pose.heading_deg = last.heading_deg;
    end.pose.sigma_m = last.pos_sigma_m;
    end.pose.heading_sigma_deg = last.heading_sigma_deg;
  }
  std::string err;
  if (tracking.getCalibration(end.calibration) != BLVD_OK) {
    std::fprintf(stderr, "vcan_drive: blvd_get_odometry_calibration: %s\n", tracking.lastError().c_str());
    return 1;
  }
  if (!opt.calibration.empty() && rc != 2 && !writeCalibration(opt.calibration, end, err)) {
    std::fprintf(stderr, "vcan_drive: %s\n", err.c_str());
    return 1;
  }
  return rc;
}

// The run's stats JSON (--stats).
nlohmann::json runStats(const Options& opt, DriveIo& io, Tracking& tracking, const Drive& d, const KeyOffState& end,
                        bool calibration_loaded, bool resumed) {
  const CanFeedStats& fs = io.feed.stats();
  const blvd_odometry_calibration& cal = end.calibration;
  nlohmann::json j;
  j["input"] = io.input.describe();
  j["tracking"] = tracking.name();
  j["package"] = opt.package;
  j["frames"] = fs.frames;
  j["mapped_frames"] = fs.mapped;
  j["can_feed"] = tracking.feedsCanFrames() ? "blvd_feed_can_frame" : "decoded";
  j["can_frames_fed"] = fs.can_frames_fed;
  j["odometry_fed"] = fs.odometry_fed;
  j["feed_errors"] = fs.feed_errors;
  j["kernel_dropped"] = io.input.kernelDropped();
  j["error_frames"] = io.input.errorFrames();
  j["bus_off"] = io.input.busOffs();
  j["link_downs"] = io.input.linkDowns();
  j["bad_lines"] = d.bad_lines;
  j["gnss_fed"] = io.gnss.fed();
  j["gnss_untimed"] = io.gnss.untimed();
  j["nmea_diagnostics"] = io.gnss.diagnostics();
  j["first_t"] = d.first_t;
  j["last_t"] = d.last_t;
  j["poses"] = d.pose_count;
  j["valid_poses"] = d.valid;
  j["matched_poses"] = d.matched;
  j["cells_visited"] = d.cells;
  j["calibration"] = {{"file", opt.calibration},
                      {"loaded", calibration_loaded},
                      {"start_pose_loaded", resumed},
                      {"start_pose_written", end.has_pose},
                      {"speed_scale", cal.speed_scale},
                      {"speed_scale_sigma", cal.speed_scale_sigma},
                      {"yaw_rate_bias_dps", cal.yaw_rate_bias_dps},
                      {"yaw_rate_bias_sigma_dps", cal.yaw_rate_bias_sigma_dps}};
  blvd_stats rs{};
  addMemoryStats(j, tracking.runtimeStats(rs) ? &rs : nullptr);
#if VCAN_DRIVE_CAPI
  addRenderStats(j, io.frames->stats());
#else
  addRenderStats(j, RenderStats{});
#endif
  return j;
}

// The tracker: a C API runtime when there is a package to render, else a
// blvd_tracker (tracking.h). Null with the reason printed.
std::unique_ptr<Tracking> openTracking(const Options& opt, const TrackingDesc& td) {
  std::string err;
  std::unique_ptr<Tracking> tracking;
#if VCAN_DRIVE_CAPI
  if (!opt.package.empty() && (!opt.no_render || !opt.render_poses.empty())) tracking = makeCapiTracking(td, err);
  else tracking = makeTrackerTracking(td, err);
#else
  (void)opt;  // this build never renders
  tracking = makeTrackerTracking(td, err);
#endif
  if (!tracking) std::fprintf(stderr, "vcan_drive: %s\n", err.c_str());
  return tracking;
}

// Opens the CAN feed and input and the JSON logs. 0, or 2 with the reason printed.
int openIo(const Options& opt, blvd_vehicle vehicle, CanFeed& feed, CanInput& input, JsonLines& poses,
           JsonLines& odolog) {
  std::string err;
  if (feed.open(opt.dbc, vehicle, err) != BLVD_OK) {
    std::fprintf(stderr, "vcan_drive: %s\n", err.c_str());
    return 2;
  }
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
  if (!poses.open(opt.poses_path, err) || !odolog.open(opt.odometry_path, err)) {
    std::fprintf(stderr, "vcan_drive: %s\n", err.c_str());
    return 2;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  CLI::App app{"vcan_drive: tracks a vehicle from its CAN bus with blvd (see samples/vcan_drive/README.md)"};
  CLI::Option* t0_opt = nullptr;
  addOptions(app, opt, t0_opt);
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
  blvd_vehicle vehicle;
  if (blvd_vehicle_from_name(opt.vehicle.c_str(), &vehicle) != BLVD_OK) {
    std::fprintf(stderr, "vcan_drive: unknown vehicle %s\n", opt.vehicle.c_str());
    return 2;
  }
  blvd_gnss_fix first_fix{};
  std::unique_ptr<Tracking> tracking = openTracking(opt, trackingDesc(opt, vehicle, gnss, first_fix));
  if (!tracking) return 2;
#if VCAN_DRIVE_CAPI
  Frames frames;
  if (tracking->canRender()) {
    if (!frames.open(*tracking, opt.frames_dir, opt.display, err)) {
      std::fprintf(stderr, "vcan_drive: %s\n", err.c_str());
      return 2;
    }
  } else if (opt.display || !opt.frames_dir.empty() || !opt.render_poses.empty()) {
    std::fprintf(stderr, "vcan_drive: --display, --frames and --render-poses need --package and rendering\n");
    return 2;
  }
  if (!opt.render_poses.empty()) return renderRecorded(opt.render_poses, opt.render_every, opt.stats_path, frames, g_stop);
#endif
  if (opt.package.empty() && opt.start.empty() && opt.nmea.empty())
    std::fprintf(stderr, "vcan_drive: no --start and no --nmea: odometry is decoded, but poses stay invalid\n");
  KeyOffState stored;
  bool calibration_loaded = false;
  if (const int rc = loadKeyOff(opt, *tracking, stored, calibration_loaded)) return rc;
  Start start = startFrom(opt, stored);

  CanFeed feed;
  CanInput input;
  JsonLines poses, odolog;
  if (const int rc = openIo(opt, vehicle, feed, input, poses, odolog)) return rc;
  DriveIo io{gnss, feed, input, poses, odolog};
#if VCAN_DRIVE_CAPI
  io.frames = &frames;
#endif
  Drive d;
  int rc = runDrive(opt, io, *tracking, start, d, wall0);
  if (!poses.close(err) || !odolog.close(err)) {
    std::fprintf(stderr, "vcan_drive: %s\n", err.c_str());
    rc = 1;
  }
  KeyOffState end;
  rc = saveKeyOff(opt, *tracking, d, end, rc);
  nlohmann::json j = runStats(opt, io, *tracking, d, end, calibration_loaded, start.resumed);
  j["wall_s"] = std::chrono::duration<double>(Clock::now() - wall0).count();
  if (!writeStats(opt.stats_path, j)) {
    std::fprintf(stderr, "vcan_drive: cannot write %s\n", opt.stats_path.c_str());
    rc = 1;
  }
  std::fprintf(stderr, "vcan_drive: %llu frames, %llu odometry samples, %llu poses (%llu valid, %llu matched) from %s\n",
               static_cast<unsigned long long>(feed.stats().frames), static_cast<unsigned long long>(feed.stats().odometry_fed),
               static_cast<unsigned long long>(d.pose_count), static_cast<unsigned long long>(d.valid),
               static_cast<unsigned long long>(d.matched), input.describe().c_str());
  return rc;
}
