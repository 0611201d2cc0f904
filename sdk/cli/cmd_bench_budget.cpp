// `blvd bench budget PKG`: the frame-time budget (Marvie seed 004)
// on a route, measured side by side in one run (the runs take turns every 64
// poses, so that a shared machine's drifting speed reaches them all alike):
//   0. blvd under a target it cannot meet: every block at its coarsest level
//      and, with --min-scale < 1, the smallest render scale: the fastest the
//      budget can make a frame (its floor);
//   1. the local model alone at full detail (LOD 0 everywhere), which must
//      exceed the target for the benchmark to mean anything;
//   2. blvd without a budget (each block at its 1-pixel-error level);
//   With --target-ms auto the target is halfway from 0's p50 to 2's on the
//   warm-up lap: one the machine can hold by choosing levels (and scale), and
//   the local model cannot.
//   3. blvd with target_frame_ms: the polygon budget from the frame-time
//      history, shared by coverage hints across the blocks' LOD chains, then
//      the render scale once the polygons are spent (docs/decisions/0008).
// It reports p50/p95 against the target, the stutter ratio (p99 of the frames
// that enter a new cell over p99 of the others) and what the budget costs in
// SSIM against run 2's image of the same pose.
#include <sys/stat.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <random>
#include <thread>

#include <nlohmann/json.hpp>

#include "cli/bench_util.h"
#include "cli/commands.h"
#include "cli/report.h"
#include "cli/route.h"
#include "imaging/metrics.h"
#include "stream/city.h"

namespace blvd::cli {
namespace {

struct BudgetOpts {
  std::string package, route = "auto:60", size = "800x480", json_path, html_dir, csv_path, target = "auto";
  uint64_t seed = 1;
  double step = 2;
  int laps = 2;
  double auto_fraction = 0.5;  // of the way from the floor's p50 to unbudgeted blvd's p50
  double min_scale = 0.5;      // the budget's lowest render scale (1: polygons only)
  uint32_t resident_cells = 0; // cell slots (0: the runtime's default)
  double fps = 0;              // display refresh the frames are paced to (0: back to back)
  double speed_kmh = 0;        // with fps: the vehicle's speed, giving the step (0: --step)
  std::string prefetch = "idle";  // blvd_runtime_desc.prefetch_priority: idle, low or anytime
  uint64_t prefetch_cpus = 0;     // blvd_runtime_desc.prefetch_cpu_mask (0: off the render thread's CPU)
  double prefetch_share = 0;      // blvd_runtime_desc.prefetch_share (0: the default 0.1; < 0: no bound)
  std::string block_reuse = "on";  // blvd_runtime_desc.block_reuse: on or off
};

// A display's refresh, as a host drawing at vsync sees it: a frame starts on
// a tick of the period, and one that overruns waits for the tick after it
// ends (the frame missed is the one a driver would see as a stutter, and its
// time is kept as measured). With period 0 the frames run back to back.
class Pacer {
 public:
  using Clock = std::chrono::steady_clock;
  explicit Pacer(double fps) : period_(fps > 0 ? Clock::duration(int64_t(1e9 / fps)) : Clock::duration::zero()) {}
  void waitTick() {
    if (period_ == Clock::duration::zero()) return;
    const Clock::time_point now = Clock::now();
    if (origin_ == Clock::time_point()) origin_ = now;
    const auto k = (now - origin_ + period_ - Clock::duration(1)) / period_;
    std::this_thread::sleep_until(origin_ + k * period_);
  }

 private:
  Clock::duration period_;
  Clock::time_point origin_{};
};

using Runtime = std::unique_ptr<blvd_runtime, void (*)(blvd_runtime*)>;

Runtime create(const BudgetOpts& o, int w, int h, blvd_render_mode mode, float target_ms, float lod_error_px,
               float min_scale = 1.f) {
  blvd_runtime_desc d{};
  d.struct_size = sizeof d;
  d.package_path = o.package.c_str();
  d.width = uint32_t(w);
  d.height = uint32_t(h);
  d.mode = mode;
  d.target_frame_ms = target_ms;
  d.lod_error_px = lod_error_px;
  d.min_render_scale = min_scale;
  d.max_resident_cells = o.resident_cells;
  d.prefetch_priority = o.prefetch == "low"       ? BLVD_PREFETCH_LOW
                        : o.prefetch == "anytime" ? BLVD_PREFETCH_IDLE_ANYTIME
                                                  : BLVD_PREFETCH_IDLE;
  d.prefetch_cpu_mask = o.prefetch_cpus;
  d.prefetch_share = float(o.prefetch_share);
  d.block_reuse = o.block_reuse == "off" ? -1 : 0;
  blvd_runtime* rt = nullptr;
  check(blvd_runtime_create(&d, &rt), nullptr, "create runtime");
  return Runtime(rt, blvd_runtime_destroy);
}

struct Frame {
  double ms;       // wall time of blvd_render (streaming, uploads, drawing, glFinish)
  bool boundary;   // the first frame in a new cell
  uint64_t tris;
  uint32_t cell;
  float scale;     // render scale the frame was drawn at
  double upload_ms;  // GL uploads inside the frame (prefetched cells)
  float aim_ms;      // what the budget aimed for (its tail margin; 0 without a target)
  uint64_t block_tris;  // triangles of the chosen block levels
  uint64_t budget;      // the polygon budget set for the next frame
  double mono_s;        // CLOCK_MONOTONIC at the frame's start, to line frames up with `perf record -k mono`
  bool degraded;        // its cell was not resident: waited for, and this is the redraw
  double prefetch_cpu_ms;  // this runtime's prediction thread's CPU since its last kept frame
  double decode_cpu_ms;    // every loader thread's of the process (all runs'), over the frame
};

// One run of the benchmark: a runtime, its kept frames and images.
struct Run {
  Runtime rt{nullptr, blvd_runtime_destroy};
  std::vector<Frame> frames;
  std::vector<std::vector<uint8_t>> images;  // every image_every-th pose, when kept
  bool want_images = false;
  uint32_t last_cell = 0xffffffffu;
  double last_prefetch_cpu_ms = 0;
  // Kept frames whose cell was not resident yet (drawn again once it was).
  size_t degraded() const {
    size_t n = 0;
    for (const Frame& f : frames) n += f.degraded;
    return n;
  }
};

// The CPU milliseconds every loader thread of the runs has spent decoding.
double decodeCpuMs(const std::vector<Run*>& all) {
  double ms = 0;
  for (Run* r : all) {
    blvd_stats st{};
    st.struct_size = sizeof st;
    check(blvd_runtime_stats(r->rt.get(), &st), r->rt.get(), "stats");
    ms += st.loader_cpu_ms + st.prefetch_cpu_ms;
  }
  return ms;
}

// Draws pose p with run r (`all`: every run of the process, for the
// loaders' CPU inside the frame). A frame whose cell is not resident yet is waited
// for and drawn again; the kept time is the second one (residency is `bench
// memory`'s subject, not this one's).
void drawPose(Run& r, const std::vector<Run*>& all, Pacer& pace, const Pose& p, bool keep, bool image, int w,
              int h) {
  blvd_runtime* rt = r.rt.get();
  pace.waitTick();
  check(blvd_set_pose_local(rt, p.x, p.y, float(p.heading_deg), 0.f), rt, "pose");
  blvd_frame_stats fs{};
  fs.struct_size = sizeof fs;
  double cpu0 = keep ? decodeCpuMs(all) : 0;
  auto t0 = std::chrono::steady_clock::now();
  check(blvd_render(rt, &fs), rt, "render");
  const bool degraded = (fs.flags & BLVD_FRAME_DEGRADED) != 0;
  if (degraded) {
    check(blvd_wait_resident(rt, 60000), rt, "wait");
    pace.waitTick();
    if (keep) cpu0 = decodeCpuMs(all);
    t0 = std::chrono::steady_clock::now();
    check(blvd_render(rt, &fs), rt, "render");
  }
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const double decode_ms = keep ? decodeCpuMs(all) - cpu0 : 0;
  const bool boundary = fs.cell != r.last_cell;
  r.last_cell = fs.cell;
  if (!keep) return;
  blvd_stats st{};
  st.struct_size = sizeof st;
  check(blvd_runtime_stats(rt, &st), rt, "stats");
  r.frames.push_back({ms, boundary, fs.triangles, fs.cell, st.render_scale, st.upload_ms, st.frame_aim_ms,
                      st.block_triangles, st.polygon_budget,
                      std::chrono::duration<double>(t0.time_since_epoch()).count(), degraded,
                      st.prefetch_cpu_ms - r.last_prefetch_cpu_ms, decode_ms});
  r.last_prefetch_cpu_ms = st.prefetch_cpu_ms;
  if (image && r.want_images) {
    r.images.emplace_back(size_t(w) * h * 4);
    check(blvd_read_pixels(rt, r.images.back().data(), r.images.back().size()), rt, "pixels");
  }
}

// One lap of the route with the runs in `runs` taking turns, kSegment poses
// each: all of them see the same machine (on a shared VM the speed drifts by
// tens of per cent within a minute, and runs made one after another would
// compare different machines), while each still draws its poses in order
// with its caches warm. A run that takes its turn first redraws its last pose
// unmeasured (its GL context was just made current again).
void lap(const std::vector<Run*>& runs, Pacer& pace, const std::vector<Pose>& poses, bool keep, size_t image_every,
         int w, int h) {
  constexpr size_t kSegment = 64;
  for (size_t s = 0; s < poses.size(); s += kSegment)
    for (Run* r : runs) {
      if (s > 0 && runs.size() > 1) drawPose(*r, runs, pace, poses[s - 1], false, false, w, h);
      for (size_t i = s; i < std::min(poses.size(), s + kSegment); ++i)
        drawPose(*r, runs, pace, poses[i], keep, i % image_every == 0, w, h);
    }
}

// The stutter ratio's spread: p5 and p95 of p99(boundary) / p99(inside) over
// bootstrap resamples of the two sets (with 41 boundary frames their p99 is
// nearly their maximum, so one slow frame moves it; decision 0008 §12).
std::pair<double, double> stutterInterval(const std::vector<double>& boundary, const std::vector<double>& inside) {
  if (boundary.empty() || inside.empty()) return {NAN, NAN};
  std::mt19937_64 rng(1);  // fixed: the same frames give the same interval
  std::vector<double> ratios, b(boundary.size()), in(inside.size());
  for (int k = 0; k < 1000; ++k) {
    for (double& x : b) x = boundary[rng() % boundary.size()];
    for (double& x : in) x = inside[rng() % inside.size()];
    ratios.push_back(pct(b, 99) / pct(in, 99));
  }
  return {pct(ratios, 5), pct(ratios, 95)};
}

// Share of the boundary (which = 1) or inside (0) frames that take at least
// 1.5 times the median of the five frames before them (tools/boundary_spikes.py).
double spikeRate(const std::vector<Frame>& f, int which) {
  size_t n = 0, spikes = 0;
  std::vector<double> prev(5);
  for (size_t i = 5; i < f.size(); ++i) {
    if (int(f[i].boundary) != which) continue;
    for (size_t k = 0; k < 5; ++k) prev[k] = f[i - 5 + k].ms;
    ++n;
    spikes += f[i].ms >= 1.5 * pct(prev, 50);
  }
  return n ? double(spikes) / double(n) : NAN;
}

std::vector<double> times(const std::vector<Frame>& f, int which /* -1 all, 0 inside, 1 boundary */) {
  std::vector<double> v;
  for (const Frame& x : f)
    if (which < 0 || int(x.boundary) == which) v.push_back(x.ms);
  return v;
}

// The four runs of one benchmark, side by side, and what they were given.
struct Bench {
  std::vector<uint32_t> route;
  std::vector<Pose> poses;
  double step = 0;
  int w = 0, h = 0;
  Run local, coarsest, unbudgeted, budgeted;
  double cal_floor = 0, cal_free = 0;  // p50s of the warm-up lap
  double target = 0;
  std::string target_rule;
};

// The route's poses every `step` metres (the distance one frame drives at
// --speed-kmh and --fps, else --step).
void routeOf(const BudgetOpts& o, Bench& b) {
  parseSize(o.size, b.w, b.h);
  const unsigned n = parseAutoRoute(o.route);
  if (o.speed_kmh > 0 && !(o.fps > 0))
    throw core::Error(core::Status::InvalidArg, "--speed-kmh needs --fps: the step is the distance driven in one frame");
  b.step = o.speed_kmh > 0 ? o.speed_kmh / 3.6 / o.fps : o.step;
  if (!(b.step > 0.01)) throw core::Error(core::Status::InvalidArg, "the step between frames must exceed 1 cm");
  stream::City city;
  std::string err;
  const core::Status st = city.open(o.package, err);
  if (st != core::Status::Ok) throw core::Error(st, err);
  if (!city.hasImpostors())
    throw core::Error(core::Status::Unsupported, o.package + " has no impostors: bake it with --impostor both");
  b.route = graph::seededRoute(city.graph(), {n, o.seed});
  b.poses = samplePoses(city.streets(), b.route, b.step);
}

// The target: given, or "auto" between the floor and the unbudgeted p50 of the warm-up lap.
void chooseTarget(const BudgetOpts& o, Bench& b) {
  if (o.target == "auto") {
    if (o.laps < 2)
      throw core::Error(core::Status::InvalidArg, "--target-ms auto is calibrated on a warm-up lap: --laps must be 2 or more");
    b.target = b.cal_floor + o.auto_fraction * (b.cal_free - b.cal_floor);
    char t[200];
    std::snprintf(t, sizeof t, "floor p50 + %.2f × (unbudgeted blvd p50 − floor p50), from the warm-up lap",
                  o.auto_fraction);
    b.target_rule = t;
  } else {
    b.target = std::stod(o.target);
    b.target_rule = "given";
  }
  if (!(b.target > 0)) throw core::Error(core::Status::InvalidArg, "--target-ms must be > 0 or auto");
}

// 0-2 side by side. A tiny error bound keeps the local model at LOD 0; a
// target no frame can meet drives every block to its coarsest level and the
// scale to its minimum (the floor). Then 3, blvd with the target: its own
// warm-up laps, and the kept lap with all four side by side.
void drive(const BudgetOpts& o, Bench& b) {
  Pacer pace(o.fps);
  const size_t image_every = std::max<size_t>(1, b.poses.size() / 40);
  std::fprintf(stderr, "bench budget: %zu cells, %zu poses; local model at LOD 0, blvd at the budget's floor and "
                       "without a budget, side by side ...\n", b.route.size(), b.poses.size());
  b.local.rt = create(o, b.w, b.h, BLVD_MODE_LOCAL, 0.f, 1e-6f);
  b.coarsest.rt = create(o, b.w, b.h, BLVD_MODE_BLVD, 0.01f, 0.f, float(o.min_scale));
  b.unbudgeted.rt = create(o, b.w, b.h, BLVD_MODE_BLVD, 0.f, 0.f);
  b.unbudgeted.want_images = b.budgeted.want_images = true;
  const std::vector<Run*> reference = {&b.local, &b.coarsest, &b.unbudgeted};
  for (Run* r : reference) check(blvd_set_route(r->rt.get(), b.route.data(), b.route.size()), r->rt.get(), "route");
  // Warm-up laps; the last one also calibrates the auto target.
  for (int l = 0; l + 1 < o.laps; ++l) lap(reference, pace, b.poses, l + 2 == o.laps, image_every, b.w, b.h);
  b.cal_floor = pct(times(b.coarsest.frames, -1), 50);
  b.cal_free = pct(times(b.unbudgeted.frames, -1), 50);
  for (Run* r : reference) r->frames.clear(), r->images.clear();
  chooseTarget(o, b);
  std::fprintf(stderr, "bench budget: blvd with a %.2f ms target ...\n", b.target);
  b.budgeted.rt = create(o, b.w, b.h, BLVD_MODE_BLVD, float(b.target), 0.f, float(o.min_scale));
  check(blvd_set_route(b.budgeted.rt.get(), b.route.data(), b.route.size()), b.budgeted.rt.get(), "route");
  for (int l = 0; l + 1 < o.laps; ++l) lap({&b.budgeted}, pace, b.poses, false, image_every, b.w, b.h);
  lap({&b.local, &b.coarsest, &b.unbudgeted, &b.budgeted}, pace, b.poses, true, image_every, b.w, b.h);
}

// Frame times, the stutter, the floor and the picture's cost, and the checks
// of the targets.
void frameFigures(const Bench& b, nlohmann::json& j) {
  const double target = b.target;
  const std::vector<double> all = times(b.budgeted.frames, -1);
  const double p50 = pct(all, 50), p95 = pct(all, 95);
  const double p99_inside = pct(times(b.budgeted.frames, 0), 99), p99_boundary = pct(times(b.budgeted.frames, 1), 99);
  const double local_p50 = pct(times(b.local.frames, -1), 50);
  std::vector<double> tris_local, tris_budget, scales, ssim;
  for (const Frame& f : b.local.frames) tris_local.push_back(double(f.tris));
  size_t scaled_frames = 0;
  for (const Frame& f : b.budgeted.frames) {
    tris_budget.push_back(double(f.tris));
    scales.push_back(f.scale);
    scaled_frames += f.scale < 1.f;
  }
  for (size_t i = 0; i < std::min(b.unbudgeted.images.size(), b.budgeted.images.size()); ++i)
    ssim.push_back(imaging::compareImages(b.unbudgeted.images[i].data(), b.budgeted.images[i].data(), b.w, b.h).ssim);
  j["target_ms"] = target;
  j["target_rule"] = b.target_rule;
  j["frame_ms_p50"] = p50;
  j["frame_ms_p95"] = p95;
  j["stutter_ratio"] = p99_boundary / p99_inside;
  j["p99_boundary_ms"] = p99_boundary;
  j["p99_inside_ms"] = p99_inside;
  j["boundary_frames"] = times(b.budgeted.frames, 1).size();  // the stutter's p99 is over these few
  const auto ci = stutterInterval(times(b.budgeted.frames, 1), times(b.budgeted.frames, 0));
  j["stutter_ratio_ci90"] = {ci.first, ci.second};
  j["boundary_spike_rate"] = spikeRate(b.budgeted.frames, 1);
  j["inside_spike_rate"] = spikeRate(b.budgeted.frames, 0);
  j["local_lod0_ms_p50"] = local_p50;
  j["floor_ms_p50"] = pct(times(b.coarsest.frames, -1), 50);
  j["floor_ms_p95"] = pct(times(b.coarsest.frames, -1), 95);
  j["calibration_floor_ms_p50"] = b.cal_floor;
  j["calibration_unbudgeted_ms_p50"] = b.cal_free;
  j["render_scale_p50"] = pct(scales, 50);
  j["render_scale_p5"] = pct(scales, 5);
  j["scaled_frames_share"] = b.budgeted.frames.empty() ? 0.0 : double(scaled_frames) / double(b.budgeted.frames.size());
  j["local_lod0_triangles_p50"] = pct(tris_local, 50);
  j["unbudgeted_ms_p50"] = pct(times(b.unbudgeted.frames, -1), 50);
  j["budgeted_triangles_p50"] = pct(tris_budget, 50);
  j["ssim_cost_p50"] = 1.0 - pct(ssim, 50);
  j["ssim_vs_unbudgeted_p50"] = pct(ssim, 50);
  j["ssim_vs_unbudgeted_p5"] = pct(ssim, 5);
  j["frames"] = b.budgeted.frames.size();
  j["checks"] = {{"local_exceeds_target", local_p50 > target},
                 {"p50_within_10pct", std::fabs(p50 - target) <= 0.1 * target},
                 {"p95_within_1_25x", p95 <= 1.25 * target},
                 {"stutter_at_most_1_2", p99_boundary / p99_inside <= 1.2}};
}

// The pacing, the prefetch and the decode work of the budgeted runtime.
void loaderFigures(const BudgetOpts& o, const Bench& b, const blvd_stats& bs, nlohmann::json& j) {
  j["min_render_scale"] = o.min_scale;
  j["budget_unreachable_at_end"] = bs.budget_unreachable != 0;
  j["route"] = b.route;  // the cells in driving order, to compare with the CSV's cells
  // The pacing: frames on a display's ticks (a host at vsync) or back to back.
  j["fps"] = o.fps;
  j["step_m"] = b.step;
  j["speed_kmh"] = o.fps > 0 ? b.step * o.fps * 3.6 : 0.0;
  j["prefetch"] = o.prefetch;
  j["prefetch_gap_waits"] = bs.prefetch_gap_waits;
  j["prefetch_gap_wait_ms"] = bs.prefetch_gap_wait_ms;
  j["prefetch_cpu_mask"] = o.prefetch_cpus;
  blvd_runtime_desc d{};
  d.struct_size = sizeof d;
  d.prefetch_share = float(o.prefetch_share);
  j["prefetch_share"] = std::round(double(blvd_runtime_desc_defaults(&d).prefetch_share) * 1e6) / 1e6;  // 0: the default
  j["prefetch_share_waits"] = bs.prefetch_share_waits;
  j["prefetch_share_wait_ms"] = bs.prefetch_share_wait_ms;
  j["prefetch_kept_off_cpu"] = bs.prefetch_kept_off_cpu;
  // Decode work: the budgeted runtime's loader threads, and the shared
  // blocks copied from another resident cell instead of decoded.
  j["block_reuse"] = o.block_reuse;
  j["blocks_reused"] = bs.blocks_reused;
  j["block_levels_copied"] = bs.block_levels_copied;
  j["loads"] = bs.loads;
  j["prefetch_cpu_ms"] = bs.prefetch_cpu_ms;
  j["loader_cpu_ms"] = bs.loader_cpu_ms;
  // Frames that found their cell not resident (each waited for and drawn
  // again, the second time kept): a prefetch that falls behind shows here.
  j["degraded_frames"] = b.budgeted.degraded();
  j["degraded_frames_unbudgeted"] = b.unbudgeted.degraded();
}

// Every frame of the kept lap of every run (--csv).
void writeCsv(const std::string& path, const Bench& b) {
  std::string csv = "run,frame,ms,upload_ms,triangles,scale,boundary,cell,aim_ms,block_triangles,polygon_budget,start_mono_s,degraded,prefetch_cpu_ms,decode_cpu_ms\n";
  const std::pair<const char*, const std::vector<Frame>*> runs[] = {
      {"local_lod0", &b.local.frames}, {"floor", &b.coarsest.frames}, {"unbudgeted", &b.unbudgeted.frames},
      {"budgeted", &b.budgeted.frames}};
  for (const auto& [name, frames] : runs)
    for (size_t i = 0; i < frames->size(); ++i) {
      const Frame& f = (*frames)[i];
      char row[256];
      std::snprintf(row, sizeof row, "%s,%zu,%.4f,%.4f,%llu,%.4f,%d,%u,%.4f,%llu,%llu,%.6f,%d,%.4f,%.4f\n", name, i, f.ms,
                    f.upload_ms, static_cast<unsigned long long>(f.tris), double(f.scale), int(f.boundary), f.cell,
                    double(f.aim_ms), static_cast<unsigned long long>(f.block_tris),
                    static_cast<unsigned long long>(f.budget), f.mono_s, int(f.degraded), f.prefetch_cpu_ms,
                    f.decode_cpu_ms);
      csv += row;
    }
  writeText(path, csv);
}

// Frame times and the budget's knobs along the route, drawn (--html).
void writeHtml(const BudgetOpts& o, const Bench& b) {
  PlotSpec ft;
  ft.title = "Frame time along the route (last lap)";
  ft.x_label = "frame";
  ft.y_label = "ms";
  Series a{"local, LOD 0", {}, ""}, u{"blvd, no budget", {}, ""}, c{"blvd, budget", {}, ""}, t{"target", {}, ""},
      m{"budget's aim", {}, ""};
  for (const Frame& f : b.local.frames) a.y.push_back(f.ms);
  for (const Frame& f : b.unbudgeted.frames) u.y.push_back(f.ms);
  for (const Frame& f : b.budgeted.frames) c.y.push_back(f.ms), t.y.push_back(b.target), m.y.push_back(f.aim_ms);
  ft.series = {a, u, c, t, m};
  PlotSpec sc;
  sc.title = "The budget's knobs along the route (last lap)";
  sc.x_label = "frame";
  sc.y_label = "render scale / share of the local model's triangles";
  Series scale{"render scale", {}, ""}, tris{"block triangles / local LOD 0", {}, ""};
  for (size_t i = 0; i < b.budgeted.frames.size(); ++i) {
    scale.y.push_back(b.budgeted.frames[i].scale);
    const double full = i < b.local.frames.size() ? double(b.local.frames[i].tris) : 0.0;
    tris.y.push_back(full > 0 ? std::min(1.0, double(b.budgeted.frames[i].tris) / full) : 0.0);
  }
  sc.series = {scale, tris};
  HtmlPage page("blvd bench budget: " + o.package);
  page.paragraph(std::to_string(b.route.size()) + " cells, " + std::to_string(b.poses.size()) + " frames a lap, " +
                 o.size + ". Target " + std::to_string(b.target) + " ms (" + b.target_rule + ").");
  page.raw(svgLinePlot(ft));
  page.raw(svgLinePlot(sc));
  std::string err;
  ::mkdir(o.html_dir.c_str(), 0755);
  if (!page.write(o.html_dir + "/index.html", err)) throw core::Error(core::Status::Io, err);
}

int runBudget(const BudgetOpts& o) {
  Bench b;
  routeOf(o, b);
  drive(o, b);
  blvd_stats bs{};
  bs.struct_size = sizeof bs;
  check(blvd_runtime_stats(b.budgeted.rt.get(), &bs), b.budgeted.rt.get(), "stats");
  nlohmann::json j;
  frameFigures(b, j);
  loaderFigures(o, b, bs, j);
  const std::string text = j.dump(2);
  std::printf("%s\n", text.c_str());
  writeText(o.json_path, text);
  if (!o.csv_path.empty()) writeCsv(o.csv_path, b);
  if (!o.html_dir.empty()) writeHtml(o, b);
  return 0;
}

}  // namespace

void addBenchBudget(CLI::App& bench, Runner& run) {
  auto o = std::make_shared<BudgetOpts>();
  auto* b = bench.add_subcommand("budget", "frame-time budget on a route: p50/p95 vs target, stutter, SSIM cost");
  b->add_option("package", o->package)->required()->check(CLI::ExistingFile);
  b->add_option("--route", o->route, "auto:N")->capture_default_str();
  b->add_option("--seed", o->seed)->capture_default_str();
  b->add_option("--step", o->step, "metres between frames")->capture_default_str();
  b->add_option("--laps", o->laps, "laps; all but the last warm up")->capture_default_str()->check(CLI::Range(1, 20));
  b->add_option("--target-ms", o->target, "frame-time target in ms, or auto (a fraction of the local model's p50)")
      ->capture_default_str();
  b->add_option("--auto-fraction", o->auto_fraction, "auto target: this far from the floor's p50 to unbudgeted blvd's p50")->capture_default_str()->check(CLI::Range(0.0, 1.0));
  b->add_option("--min-scale", o->min_scale, "lowest render scale the budget may use (1: polygons only)")
      ->capture_default_str()->check(CLI::Range(0.25, 1.0));
  b->add_option("--fps", o->fps, "pace the frames to a display refresh of this rate, as a host at vsync (0: back to back)")
      ->capture_default_str()->check(CLI::Range(0.0, 1000.0));
  b->add_option("--speed-kmh", o->speed_kmh, "with --fps: the vehicle's speed, which sets the step (0: --step)")
      ->capture_default_str()->check(CLI::Range(0.0, 1000.0));
  b->add_option("--prefetch", o->prefetch,
                "predictions: idle (SCHED_IDLE, in the gaps between paced frames), anytime (SCHED_IDLE only), low "
                "(nice 19)")
      ->capture_default_str()->check(CLI::IsMember({"idle", "anytime", "low"}));
  b->add_option("--prefetch-cpus", o->prefetch_cpus,
                "CPU mask of the prediction threads (bit i: CPU i; 0x3 lets them share the render thread's CPU on "
                "2 cores); 0: every CPU but the render thread's")
      ->capture_default_str();
  b->add_option("--prefetch-share", o->prefetch_share,
                "the most of the wall time the process's predictions may decode (0: the runtime's 0.1; -1: no bound)")
      ->capture_default_str()->check(CLI::Range(-1.0, 1.0));
  b->add_option("--block-reuse", o->block_reuse,
                "copy the blocks a new cell shares with a resident one GPU-side (on) or decode them again (off)")
      ->capture_default_str()->check(CLI::IsMember({"on", "off"}));
  b->add_option("--size", o->size)->capture_default_str();
  b->add_option("--resident-cells", o->resident_cells, "cell slots (0: the runtime's default)")->capture_default_str();
  b->add_option("--json", o->json_path, "write the JSON here too");
  b->add_option("--html", o->html_dir, "write an HTML page with the frame-time plot");
  b->add_option("--csv", o->csv_path, "write every kept frame of every run (time, uploads, triangles, scale)");
  b->callback([o, &run] { run = [o] { return runBudget(*o); }; });
}

}  // namespace blvd::cli
