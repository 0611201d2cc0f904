// gnss_replay: an NMEA log in, frames out.
//
//   NMEA 0183 log -> adapters/replay (adapters/gnss parser) -> blvd_feed_gnss
//     -> per tick of the log's clock: blvd_get_pose (poses.jsonl),
//        blvd_render + blvd_read_pixels (frames/frame_NNNNNN.png)
//     -> stats.json (frames, cells visited, frame-time percentiles, degraded
//        frames, blvd_runtime_stats)
//
// Everything runs on the log's clock (UTC of its fixes), from its first
// position fix: as fast as it renders, or paced on the wall clock with
// --realtime. See README.md.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "blvd/blvd.h"
#include "common/backend.h"
#include "common/logs.h"
#include "common/memory.h"
#include "frame_writer.h"
#include "replay/replayer.h"

namespace {

using Clock = std::chrono::steady_clock;

volatile std::sig_atomic_t g_stop = 0;  // SIGINT/SIGTERM
void onSignal(int) { g_stop = 1; }

struct Options {
  std::string nmea, package, frames_dir, poses_path, stats_path;
  double fps = 10, pose_interval_s = 0.1, duration_s = 0;
  bool realtime = false, strict = false;
  double speed = 1;
  double frame_wait_ms = -1;  // < 0: 2000 as fast as possible, 0 with --realtime
  uint32_t width = 800, height = 480;
  std::string backend = "auto";
};

// The runtime, destroyed on every way out of main.
struct Runtime {
  blvd_runtime* rt = nullptr;
  ~Runtime() { blvd_runtime_destroy(rt); }
};

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app{"gnss_replay: an NMEA log in, tracked poses and rendered frames out (samples/gnss_replay/README.md)"};
  app.add_option("nmea", o.nmea, "NMEA 0183 log (RMC/GGA/GST ...; RMC or ZDA gives the date)")->required();
  app.add_option("--package", o.package, "a .blvd package (blvd bake)")->required();
  app.add_option("--frames", o.frames_dir, "write the frames as PNG into this folder");
  app.add_option("--poses", o.poses_path, "write the tracked poses as JSON lines");
  app.add_option("--stats", o.stats_path, "write the run's stats JSON");
  app.add_option("--fps", o.fps, "frames per second of log time")->capture_default_str()->check(CLI::Range(0.1, 120.0));
  app.add_option("--pose-interval", o.pose_interval_s, "seconds of log time between poses")
      ->capture_default_str()
      ->check(CLI::Range(0.001, 60.0));
  app.add_option("--duration", o.duration_s, "replay only this many seconds of the log (0: all)")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--realtime", o.realtime, "pace the log on the wall clock (as a receiver would send it)");
  app.add_option("--speed", o.speed, "with --realtime: log seconds per wall second")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 1000.0));
  app.add_flag("--strict", o.strict, "stop at the first malformed sentence instead of skipping it");
  app.add_option("--frame-wait", o.frame_wait_ms,
                 "ms a frame may wait for its cell to load (default 2000; 0 with --realtime: never, as a live display)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--backend", o.backend, "auto, surfaceless, device or osmesa")
      ->capture_default_str()
      ->check(CLI::IsMember(samples::backendNames()));
  app.add_option("--width", o.width)->capture_default_str()->check(CLI::Range(16u, 8192u));
  app.add_option("--height", o.height)->capture_default_str()->check(CLI::Range(16u, 8192u));
  CLI11_PARSE(app, argc, argv);
  if (o.frame_wait_ms < 0) o.frame_wait_ms = o.realtime ? 0 : 2000;

  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  const auto wall0 = Clock::now();
  std::string err;

  // Inputs first, each failure naming its file.
  blvd::replay::ReplayDesc rd;
  rd.nmea_path = o.nmea;
  rd.strict = o.strict;
  blvd::replay::Replayer replayer;
  if (replayer.open(rd, err) != BLVD_OK) {
    std::fprintf(stderr, "gnss_replay: %s\n", err.c_str());
    return 2;
  }
  blvd_runtime_desc d{};
  d.struct_size = sizeof d;
  d.package_path = o.package.c_str();
  d.width = o.width;
  d.height = o.height;
  d.backend = samples::parseBackend(o.backend);
  Runtime runtime;
  if (blvd_runtime_create(&d, &runtime.rt) != BLVD_OK) {
    std::fprintf(stderr, "gnss_replay: package %s: %s\n", o.package.c_str(), blvd_last_error(nullptr));
    return 2;
  }
  blvd_runtime* rt = runtime.rt;
  blvd_set_camera_source(rt, BLVD_CAMERA_TRACKED);  // frames follow the tracked vehicle
  gnss_replay::FrameWriter frames;
  samples::JsonLines poses;
  if (!frames.open(rt, o.width, o.height, o.frames_dir, o.frame_wait_ms, err) || !poses.open(o.poses_path, err)) {
    std::fprintf(stderr, "gnss_replay: %s\n", err.c_str());
    return 2;
  }

  // The log's clock starts at its first position fix: before it there is nothing to draw.
  bool started = false;
  double t0 = 0, last_t = 0, next_frame_t = 0, next_pose_t = 0;
  Clock::time_point pace0;  // wall time of t0
  uint64_t fixes = 0, position_fixes = 0, feed_errors = 0, pose_count = 0, valid = 0, matched = 0;
  size_t warned = 0;
  std::vector<uint32_t> cells;
  int rc = 0;
  const auto printWarnings = [&] {
    const std::vector<std::string>& w = replayer.warnings();
    for (; warned < w.size(); ++warned) std::fprintf(stderr, "gnss_replay: %s\n", w[warned].c_str());
  };
  // Sleeps until log time t is due on the wall clock (--realtime).
  const auto pace = [&](double t) {
    if (!o.realtime) return;
    std::this_thread::sleep_until(pace0 + std::chrono::duration_cast<Clock::duration>(
                                              std::chrono::duration<double>((t - t0) / o.speed)));
  };
  // Poses and frames whose time is before `until` (up to it, inclusive, at the end).
  const auto tick = [&](double until, bool inclusive) {
    for (;;) {
      const double t = std::min(next_pose_t, next_frame_t);
      if (g_stop || t > until || (!inclusive && t == until)) return true;
      pace(t);
      if (next_pose_t <= next_frame_t) {
        blvd_pose p{};
        p.struct_size = sizeof p;
        if (blvd_get_pose(rt, t, &p) != BLVD_OK) {
          err = std::string("blvd_get_pose: ") + blvd_last_error(rt);
          return false;
        }
        poses.pose(p);
        ++pose_count;
        valid += (p.flags & BLVD_POSE_VALID) != 0;
        matched += (p.flags & BLVD_POSE_MATCHED) != 0;
        samples::noteCell(cells, p);
        next_pose_t = t0 + double(pose_count) * o.pose_interval_s;
      } else {
        if (!frames.frame(err)) return false;
        next_frame_t = t0 + double(frames.stats().frames) / o.fps;
      }
    }
  };

  blvd::replay::Event ev;
  while (!g_stop) {
    const blvd::replay::Replayer::Step step = replayer.next(ev);
    printWarnings();
    if (step == blvd::replay::Replayer::Step::Error) {
      // --strict: the malformed line was just listed; a read error was not.
      const std::vector<std::string>& w = replayer.warnings();
      if (o.strict && !w.empty() && w.back() == replayer.error())
        std::fprintf(stderr, "gnss_replay: stopped at that line (--strict)\n");
      else
        std::fprintf(stderr, "gnss_replay: %s\n", replayer.error().c_str());
      rc = 1;
      break;
    }
    const bool end = step == blvd::replay::Replayer::Step::End ||
                     (started && o.duration_s > 0 && ev.t > t0 + o.duration_s);
    if (started && !tick(end ? last_t : ev.t, end)) {
      std::fprintf(stderr, "gnss_replay: %s\n", err.c_str());
      rc = 1;
      break;
    }
    if (end) break;
    if (ev.type != blvd::replay::EventType::Gnss) continue;
    ++fixes;
    if (ev.gnss.flags & BLVD_GNSS_HAS_LATLON) {
      ++position_fixes;
      if (!started) {
        started = true;
        t0 = next_frame_t = next_pose_t = ev.t;
        pace0 = Clock::now();
      }
    }
    if (started) pace(ev.t);
    if (blvd_feed_gnss(rt, &ev.gnss) != BLVD_OK) ++feed_errors;
    last_t = ev.t;
  }
  if (!poses.close(err)) {
    std::fprintf(stderr, "gnss_replay: %s\n", err.c_str());
    rc = 1;
  }
  const blvd::replay::Replayer::Stats& rs = replayer.stats();
  if (rc == 0 && position_fixes == 0) {
    std::fprintf(stderr, "gnss_replay: %s: no position fix in %llu fixes (%llu without a date, %llu malformed lines%s)\n",
                 o.nmea.c_str(), static_cast<unsigned long long>(fixes),
                 static_cast<unsigned long long>(rs.gnss_untimed), static_cast<unsigned long long>(rs.bad_lines),
                 rs.bad_lines ? ", listed above" : "");
    rc = 1;
  }

  blvd_stats st{};
  st.struct_size = sizeof st;
  const bool have_st = blvd_runtime_stats(rt, &st) == BLVD_OK;
  nlohmann::json j;
  j["nmea"] = o.nmea;
  j["package"] = o.package;
  j["realtime"] = o.realtime;
  j["fps"] = o.fps;
  j["fixes"] = fixes;
  j["position_fixes"] = position_fixes;
  j["fixes_without_date"] = rs.gnss_untimed;
  j["feed_errors"] = feed_errors;
  j["malformed_lines"] = rs.bad_lines;
  j["malformed"] = replayer.warnings();  // the first Replayer::kMaxWarnings, "file:line: reason"
  j["first_t"] = t0;
  j["last_t"] = last_t;
  j["poses"] = pose_count;
  j["valid_poses"] = valid;
  j["matched_poses"] = matched;
  j["cells_visited"] = cells;
  samples::addRenderStats(j, frames.stats());
  j["frame_wait_ms"] = o.frame_wait_ms;
  j["frame_wait_timeouts"] = frames.waitTimeouts();
  samples::addMemoryStats(j, have_st ? &st : nullptr);
  if (have_st) {
    j["runtime_frames"] = st.frames;
    j["upload_ms_max"] = st.upload_ms_max;
  }
  j["wall_s"] = std::chrono::duration<double>(Clock::now() - wall0).count();
  if (!samples::writeStats(o.stats_path, j)) {
    std::fprintf(stderr, "gnss_replay: cannot write %s\n", o.stats_path.c_str());
    rc = 1;
  }
  std::fprintf(stderr,
               "gnss_replay: %llu fixes (%llu with a position, %llu malformed lines) over %.1f s of log: %llu poses "
               "(%llu matched, %zu cells), %llu frames (%llu degraded, %llu blank)\n",
               static_cast<unsigned long long>(fixes), static_cast<unsigned long long>(position_fixes),
               static_cast<unsigned long long>(rs.bad_lines), last_t - t0, static_cast<unsigned long long>(pose_count),
               static_cast<unsigned long long>(matched), cells.size(),
               static_cast<unsigned long long>(frames.stats().frames), static_cast<unsigned long long>(frames.stats().degraded),
               static_cast<unsigned long long>(frames.stats().blank));
  return rc;
}
