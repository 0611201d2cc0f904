// `blvd bench stream PKG --url URL --profile 56k|1m|10m`: a drive along a
// 200-cell route at 50 km/h from a package on a server, from a cold cache,
// in simulated time: the vehicle advances `--time-scale` simulated seconds
// per wall second, and the server's link (nginx limit_rate, set by
// packaging/scripts/bench_stream.sh) runs at the profile's rate times the
// same factor, so that bytes per simulated second are the profile's. Reports
// what a driver sees (the share of degraded frames, after the first cell),
// bytes and requests per km, the time to the first frame, the cache's peak
// and how far ahead it reaches. PKG is the same package on local disk, for
// the route.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <thread>

#include <nlohmann/json.hpp>

#include "cli/bench_util.h"
#include "cli/commands.h"
#include "cli/route.h"
#include "stream/city.h"

namespace blvd::cli {
namespace {

using Clock = std::chrono::steady_clock;

struct StreamOpts {
  std::string package, url, profile = "1m", cache, size = "160x96", json_path;
  unsigned cells = 200;
  uint64_t seed = 1;
  double speed_kmh = 50, fps = 10, time_scale = 10;
  uint64_t cache_bytes = 64ull << 20;
};

double profileBitsPerS(const std::string& p) {
  if (p == "56k") return 56e3;
  if (p == "1m") return 1e6;
  if (p == "10m") return 10e6;
  throw core::Error(core::Status::InvalidArg, "--profile must be 56k, 1m or 10m");
}

struct Tally {
  uint64_t frames = 0, degraded = 0, frames_after = 0, degraded_after = 0;
  uint64_t peak_cache = 0;
  std::vector<double> ahead_s;
};

double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

blvd_frame_stats renderAt(blvd_runtime* rt, const Pose& p) {
  check(blvd_set_pose_local(rt, p.x, p.y, float(p.heading_deg), 0.f), rt, "pose");
  blvd_frame_stats fs{};
  fs.struct_size = sizeof fs;
  check(blvd_render(rt, &fs), rt, "render");
  return fs;
}

blvd_stats statsOf(blvd_runtime* rt) {
  blvd_stats s{};
  s.struct_size = sizeof s;
  check(blvd_runtime_stats(rt, &s), rt, "stats");
  return s;
}

using Runtime = std::unique_ptr<blvd_runtime, void (*)(blvd_runtime*)>;

// Creates a runtime from `d` into rt and draws until the first pose's frame
// is whole; the wall seconds that took.
double firstFrame(const blvd_runtime_desc& d, const std::vector<uint32_t>& route, const Pose& p, Runtime& rt) {
  const auto t0 = Clock::now();
  blvd_runtime* raw = nullptr;
  check(blvd_runtime_create(&d, &raw), nullptr, "create");
  rt.reset(raw);
  check(blvd_set_route(raw, route.data(), route.size()), raw, "route");
  while (renderAt(raw, p).flags & BLVD_FRAME_DEGRADED) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  return seconds(t0, Clock::now());
}

// The drive: the pose of the simulated time now, frame after frame, until the route ends.
void drive(blvd_runtime* rt, const std::vector<Pose>& poses, const StreamOpts& o, Tally& t) {
  const double speed = o.speed_kmh / 3.6;
  const uint32_t first_cell = poses.front().cell;
  bool left_first = false;  // past the first cell: the goal is no degraded frame from here
  const auto t0 = Clock::now();
  for (;;) {
    const size_t i = size_t(seconds(t0, Clock::now()) * o.time_scale * o.fps);
    if (i >= poses.size()) break;
    const blvd_frame_stats fs = renderAt(rt, poses[i]);
    const bool degraded = fs.flags & BLVD_FRAME_DEGRADED;
    ++t.frames, t.degraded += degraded;
    left_first |= poses[i].cell != first_cell;
    if (left_first) ++t.frames_after, t.degraded_after += degraded;
    const blvd_stats s = statsOf(rt);
    t.peak_cache = std::max(t.peak_cache, s.cache_bytes);
    t.ahead_s.push_back(s.cached_ahead_m / speed);
  }
}

int runStream(const StreamOpts& o) {
  const double bits = profileBitsPerS(o.profile);
  int w = 0, h = 0;
  parseSize(o.size, w, h);
  if (!stream::City::isUrl(o.url)) throw core::Error(core::Status::InvalidArg, "--url must be http:// or https://");
  std::vector<uint32_t> route;
  std::vector<Pose> poses;
  {
    stream::City city;
    std::string err;
    const core::Status st = city.open(o.package, err);
    if (st != core::Status::Ok) throw core::Error(st, err);
    // The longest of 64 seeded tries: a route ends where only a tunnel goes on (Monaco has many).
    route = graph::seededRoute(city.graph(), {o.cells, o.seed, graph::kNone, true, 64});
    poses = samplePoses(city.streets(), route, o.speed_kmh / 3.6 / o.fps);
  }
  const std::string cache = o.cache.empty() ? (std::filesystem::temp_directory_path() / "blvd-bench-stream").string() : o.cache;
  std::filesystem::remove_all(cache);  // a cold start
  blvd_runtime_desc d{};
  d.struct_size = sizeof d;
  d.package_path = o.url.c_str();
  d.cache_path = cache.c_str();
  d.cache_bytes = o.cache_bytes;
  // The client paces too, each request from its first byte: nginx's limit_rate lets a small
  // response (a block blob) through at full speed.
  d.link_max_bytes_per_s = uint64_t(bits * o.time_scale / 8);
  d.width = uint32_t(w), d.height = uint32_t(h);
  Runtime rt(nullptr, blvd_runtime_destroy);
  const double cold_wall = firstFrame(d, route, poses.front(), rt);
  const blvd_stats cold = statsOf(rt.get());
  Tally t;
  drive(rt.get(), poses, o, t);
  const blvd_stats s = statsOf(rt.get());
  rt.reset();
  // The same start from the cache, offline: what the first frame costs
  // without the link (create, GL, decode), which the time scale must not
  // stretch.
  d.link_mode = BLVD_LINK_OFFLINE;
  const double warm_wall = firstFrame(d, route, poses.front(), rt);
  const double ttff_s = warm_wall + std::max(0.0, cold_wall - warm_wall) * o.time_scale;
  const double km = double(poses.size()) * (o.speed_kmh / 3.6 / o.fps) / 1000.0;
  nlohmann::json j;
  j["profile"] = o.profile;
  j["link_bits_per_s"] = bits;
  j["time_scale"] = o.time_scale;
  j["route_cells"] = route.size();
  j["route_km"] = km;
  j["frames"] = t.frames;
  j["degraded_share"] = t.frames ? double(t.degraded) / double(t.frames) : 0.0;
  j["degraded_share_after_first_cell"] = t.frames_after ? double(t.degraded_after) / double(t.frames_after) : 0.0;
  j["bytes_per_km"] = double(s.link_bytes) / km;
  j["requests_per_km"] = double(s.link_requests) / km;
  j["bytes_per_km_after_start"] = double(s.link_bytes - cold.link_bytes) / km;
  j["cold_start_bytes"] = cold.link_bytes;
  j["cold_start_requests"] = cold.link_requests;
  j["time_to_first_frame_s"] = ttff_s;  // warm start + the cold start's extra wall time x the time scale
  j["warm_start_s"] = warm_wall;
  j["peak_cache_bytes"] = t.peak_cache;
  j["cache_bytes"] = o.cache_bytes;
  j["cached_ahead_s_p5"] = pct(t.ahead_s, 5);
  j["cached_ahead_s_p50"] = pct(t.ahead_s, 50);
  j["link_waits"] = s.link_waits;
  j["load_errors"] = s.load_errors;
  std::printf("%s\n", j.dump(2).c_str());
  writeText(o.json_path, j.dump(2));
  return s.load_errors == 0 ? 0 : 1;
}

}  // namespace

void addBenchStream(CLI::App& bench, Runner& run) {
  auto o = std::make_shared<StreamOpts>();
  auto* b = bench.add_subcommand("stream", "drive a route from a package on a server, cold cache, simulated time");
  b->add_option("package", o->package, "the same package on local disk (for the route)")->required()->check(CLI::ExistingFile);
  b->add_option("--url", o->url, "the package on the server")->required();
  b->add_option("--profile", o->profile, "the link: 56k, 1m or 10m (the server's rate is this times --time-scale)")
      ->capture_default_str()->check(CLI::IsMember({"56k", "1m", "10m"}));
  b->add_option("--time-scale", o->time_scale, "simulated seconds per wall second")->capture_default_str()->check(CLI::Range(0.1, 1000.0));
  b->add_option("--cells", o->cells, "route length in cells")->capture_default_str()->check(CLI::Range(2u, 100000u));
  b->add_option("--seed", o->seed)->capture_default_str();
  b->add_option("--speed-kmh", o->speed_kmh)->capture_default_str()->check(CLI::Range(1.0, 300.0));
  b->add_option("--fps", o->fps, "simulated frames per second")->capture_default_str()->check(CLI::Range(1.0, 240.0));
  b->add_option("--cache", o->cache, "cache folder (emptied first; default: a temporary one)");
  b->add_option("--cache-bytes", o->cache_bytes)->capture_default_str();
  b->add_option("--size", o->size)->capture_default_str();
  b->add_option("--json", o->json_path, "write the JSON here too");
  b->callback([o, &run] { run = [o] { return runStream(*o); }; });
}

}  // namespace blvd::cli
