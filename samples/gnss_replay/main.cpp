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

void addOptions(CLI::App& app, Options& o) {
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
}

// The replay on the log's clock, which starts at its first position fix:
// before it there is nothing to draw.
class Replay {
 public:
  Replay(const Options& o, blvd::replay::Replayer& replayer, blvd_runtime* rt, gnss_replay::FrameWriter& frames,
         samples::JsonLines& poses)
      : o_(o), replayer_(replayer), rt_(rt), frames_(frames), poses_(poses) {}
  // Until the log ends, --duration is reached, or something fails (1).
  int run();
  // Fails (1) when the log held no position fix.
  int checkFixes() const;
  nlohmann::json stats() const;
  void summary() const;

 private:
  bool tick(double until, bool inclusive, std::string& err);
  bool pose(double t, std::string& err);
  void pace(double t) const;
  void feed(const blvd::replay::Event& ev);
  void printWarnings();

  const Options& o_;
  blvd::replay::Replayer& replayer_;
  blvd_runtime* rt_;
  gnss_replay::FrameWriter& frames_;
  samples::JsonLines& poses_;
  bool started_ = false;
  double t0_ = 0, last_t_ = 0, next_frame_t_ = 0, next_pose_t_ = 0;
  Clock::time_point pace0_;  // wall time of t0
  uint64_t fixes_ = 0, position_fixes_ = 0, feed_errors_ = 0, pose_count_ = 0, valid_ = 0, matched_ = 0;
  size_t warned_ = 0;
  std::vector<uint32_t> cells_;
};

void Replay::printWarnings() {
  const std::vector<std::string>& w = replayer_.warnings();
  for (; warned_ < w.size(); ++warned_) std::fprintf(stderr, "gnss_replay: %s\n", w[warned_].c_str());
}

// Sleeps until log time t is due on the wall clock (--realtime).
void Replay::pace(double t) const {
  if (!o_.realtime) return;
  std::this_thread::sleep_until(pace0_ + std::chrono::duration_cast<Clock::duration>(
                                             std::chrono::duration<double>((t - t0_) / o_.speed)));
}

bool Replay::pose(double t, std::string& err) {
  blvd_pose p{};
  p.struct_size = sizeof p;
  if (blvd_get_pose(rt_, t, &p) != BLVD_OK) {
    err = std::string("blvd_get_pose: ") + blvd_last_error(rt_);
    return false;
  }
  poses_.pose(p);
  ++pose_count_;
  valid_ += (p.flags & BLVD_POSE_VALID) != 0;
  matched_ += (p.flags & BLVD_POSE_MATCHED) != 0;
  samples::noteCell(cells_, p);
  next_pose_t_ = t0_ + double(pose_count_) * o_.pose_interval_s;
  return true;
}

// Poses and frames whose time is before `until` (up to it, inclusive, at the end).
bool Replay::tick(double until, bool inclusive, std::string& err) {
  for (;;) {
    const double t = std::min(next_pose_t_, next_frame_t_);
    if (g_stop || t > until || (!inclusive && t == until)) return true;
    pace(t);
    if (next_pose_t_ <= next_frame_t_) {
      if (!pose(t, err)) return false;
    } else {
      if (!frames_.frame(err)) return false;
      next_frame_t_ = t0_ + double(frames_.stats().frames) / o_.fps;
    }
  }
}

void Replay::feed(const blvd::replay::Event& ev) {
  ++fixes_;
  if (ev.gnss.flags & BLVD_GNSS_HAS_LATLON) {
    ++position_fixes_;
    if (!started_) {
      started_ = true;
      t0_ = next_frame_t_ = next_pose_t_ = ev.t;
      pace0_ = Clock::now();
    }
  }
  if (started_) pace(ev.t);
  if (blvd_feed_gnss(rt_, &ev.gnss) != BLVD_OK) ++feed_errors_;
  last_t_ = ev.t;
}

int Replay::run() {
  blvd::replay::Event ev;
  std::string err;
  while (!g_stop) {
    const blvd::replay::Replayer::Step step = replayer_.next(ev);
    printWarnings();
    if (step == blvd::replay::Replayer::Step::Error) {
      // --strict: the malformed line was just listed; a read error was not.
      const std::vector<std::string>& w = replayer_.warnings();
      if (o_.strict && !w.empty() && w.back() == replayer_.error())
        std::fprintf(stderr, "gnss_replay: stopped at that line (--strict)\n");
      else
        std::fprintf(stderr, "gnss_replay: %s\n", replayer_.error().c_str());
      return 1;
    }
    const bool end = step == blvd::replay::Replayer::Step::End ||
                     (started_ && o_.duration_s > 0 && ev.t > t0_ + o_.duration_s);
    if (started_ && !tick(end ? last_t_ : ev.t, end, err)) {
      std::fprintf(stderr, "gnss_replay: %s\n", err.c_str());
      return 1;
    }
    if (end) break;
    if (ev.type == blvd::replay::EventType::Gnss) feed(ev);
  }
  return 0;
}

int Replay::checkFixes() const {
  if (position_fixes_ > 0) return 0;
  const blvd::replay::Replayer::Stats& rs = replayer_.stats();
  std::fprintf(stderr, "gnss_replay: %s: no position fix in %llu fixes (%llu without a date, %llu malformed lines%s)\n",
               o_.nmea.c_str(), static_cast<unsigned long long>(fixes_), static_cast<unsigned long long>(rs.gnss_untimed),
               static_cast<unsigned long long>(rs.bad_lines), rs.bad_lines ? ", listed above" : "");
  return 1;
}

nlohmann::json Replay::stats() const {
  blvd_stats st{};
  st.struct_size = sizeof st;
  const bool have_st = blvd_runtime_stats(rt_, &st) == BLVD_OK;
  const blvd::replay::Replayer::Stats& rs = replayer_.stats();
  nlohmann::json j;
  j["nmea"] = o_.nmea;
  j["package"] = o_.package;
  j["realtime"] = o_.realtime;
  j["fps"] = o_.fps;
  j["fixes"] = fixes_;
  j["position_fixes"] = position_fixes_;
  j["fixes_without_date"] = rs.gnss_untimed;
  j["feed_errors"] = feed_errors_;
  j["malformed_lines"] = rs.bad_lines;
  j["malformed"] = replayer_.warnings();  // the first Replayer::kMaxWarnings, "file:line: reason"
  j["first_t"] = t0_;
  j["last_t"] = last_t_;
  j["poses"] = pose_count_;
  j["valid_poses"] = valid_;
  j["matched_poses"] = matched_;
  j["cells_visited"] = cells_;
  samples::addRenderStats(j, frames_.stats());
  j["frame_wait_ms"] = o_.frame_wait_ms;
  j["frame_wait_timeouts"] = frames_.waitTimeouts();
  samples::addMemoryStats(j, have_st ? &st : nullptr);
  if (have_st) {
    j["runtime_frames"] = st.frames;
    j["upload_ms_max"] = st.upload_ms_max;
  }
  return j;
}

void Replay::summary() const {
  const auto& fs = frames_.stats();
  std::fprintf(stderr,
               "gnss_replay: %llu fixes (%llu with a position, %llu malformed lines) over %.1f s of log: %llu poses "
               "(%llu matched, %zu cells), %llu frames (%llu degraded, %llu blank)\n",
               static_cast<unsigned long long>(fixes_), static_cast<unsigned long long>(position_fixes_),
               static_cast<unsigned long long>(replayer_.stats().bad_lines), last_t_ - t0_,
               static_cast<unsigned long long>(pose_count_), static_cast<unsigned long long>(matched_), cells_.size(),
               static_cast<unsigned long long>(fs.frames), static_cast<unsigned long long>(fs.degraded),
               static_cast<unsigned long long>(fs.blank));
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app{"gnss_replay: an NMEA log in, tracked poses and rendered frames out (samples/gnss_replay/README.md)"};
  addOptions(app, o);
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

  Replay replay(o, replayer, rt, frames, poses);
  int rc = replay.run();
  if (!poses.close(err)) {
    std::fprintf(stderr, "gnss_replay: %s\n", err.c_str());
    rc = 1;
  }
  if (rc == 0) rc = replay.checkFixes();
  nlohmann::json j = replay.stats();
  j["wall_s"] = std::chrono::duration<double>(Clock::now() - wall0).count();
  if (!samples::writeStats(o.stats_path, j)) {
    std::fprintf(stderr, "gnss_replay: cannot write %s\n", o.stats_path.c_str());
    rc = 1;
  }
  replay.summary();
  return rc;
}
