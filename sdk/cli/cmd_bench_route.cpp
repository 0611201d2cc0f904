// `blvd bench route`: drives the camera along a path of connected cells and
// renders every pose in every mode side by side in one run, so the reported
// figures are ratios on one machine (full model vs blvd, and the baselines),
// plus fidelity against the full model's image of the same pose: over the
// whole frame (SSIM, PSNR, bad pixels) and where the far city is
// (far_metrics.h: far_bad, holes, spurious, missing objects, visibility error).
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include <nlohmann/json.hpp>

#include "blvd/blvd.h"
#include "cli/bench_route.h"
#include "cli/bench_util.h"
#include "cli/far_metrics.h"
#include "cli/report.h"
#include "cli/route.h"
#include "core/status.h"
#include "imaging/image.h"
#include "imaging/metrics.h"
#include "stream/city.h"

namespace blvd::cli {
namespace {

struct Mode {
  const char* key;
  blvd_render_mode mode;
  float radius;
};
constexpr Mode kModes[] = {{"full", BLVD_MODE_FULL, 0},       {"local", BLVD_MODE_LOCAL, 0},
                       {"radius100", BLVD_MODE_RADIUS, 100}, {"radius250", BLVD_MODE_RADIUS, 250},
                       {"single", BLVD_MODE_SINGLE, 0},   {"blvd", BLVD_MODE_BLVD, 0}};
constexpr size_t kNumModes = sizeof kModes / sizeof kModes[0];
constexpr size_t kBlvd = kNumModes - 1;
constexpr size_t kSingle = kNumModes - 2;
static_assert(kModes[kBlvd].mode == BLVD_MODE_BLVD && kModes[kSingle].mode == BLVD_MODE_SINGLE);
constexpr size_t kWorstFrames = 12;

struct Sample {
  double ms = 0, tris = 0, ssim = 1, psnr = INFINITY, bad = 0;
  double far_bad = 0, holes = 0, spurious = 0, vis_px = 0, sil_px = 0;
  std::vector<MissingObject> missing;  // missing objects, with what shows on their pixels
  uint32_t cell = 0;  // the runtime's cell for the pose
  uint64_t far_px = 0;
};

// far_bad is a share of the far region; a pose whose far region is under 1 %
// of the frame (a few distant roofs) gives a share of a handful of pixels, so
// its far_bad is left out of the percentiles (holes and spurious, shares of
// the frame, keep every pose).
constexpr double kFarBadMinShare = 0.01;

// A frame kept for the worst-frames gallery.
struct Kept {
  size_t pose = 0;
  double score = 0;  // far_bad + spurious
  std::vector<uint8_t> full, blvd, overlay;
  std::vector<uint32_t> missing;
};

std::string fmt(double v, int d) {
  char b[32];
  std::snprintf(b, sizeof b, "%.*f", d, v);
  return b;
}

// The far-metric inputs of `mode` at a pose whose runtime cell is `cell`.
FarInputs farInputs(const stream::City& city, uint32_t cell, blvd_render_mode mode) {
  FarInputs in;
  const graph::StreetGraph& g = city.graph();
  const uint32_t* lb = cell < g.cellCount() ? g.local_blocks.begin(cell) : nullptr;
  const uint32_t* le = cell < g.cellCount() ? g.local_blocks.end(cell) : nullptr;
  in.is_local = [lb, le](uint32_t b) { return lb && std::find(lb, le, b) != le; };
  if ((mode == BLVD_MODE_BLVD || mode == BLVD_MODE_SINGLE) && cell < city.cellTables().impostors.size()) {
    const auto& ci = city.cellTables().impostors[cell];
    const auto* layers = mode == BLVD_MODE_SINGLE ? &ci.single : &ci.layered;
    in.layer_holds = [layers](uint32_t layer, uint32_t b) {
      if (layer >= layers->size()) return false;
      const auto& bl = (*layers)[layer].blocks;
      return std::binary_search(bl.begin(), bl.end(), b);
    };
  }
  return in;
}

std::string viewCommand(const RouteBenchOpts& o, const stream::City& city, const Pose& p, const char* mode) {
  double lat = 0, lon = 0, hgt = 0;
  city.frame().reverse({p.x, p.y, 0.0}, lat, lon, hgt);
  char b[512];
  // 0.1 mm and 0.0001°: far ground seen edge-on changes with less than the
  // 0.05° a heading of one decimal would move it.
  std::snprintf(b, sizeof b, "blvd view %s --lat %.9f --lon %.9f --heading %.4f --size %s --mode %s -o %s.png",
                o.package.c_str(), lat, lon, p.heading_deg, o.size.c_str(), mode, mode);
  return b;
}

void keepWorst(std::vector<Kept>& worst, Kept k) {
  if (worst.size() == kWorstFrames && k.score <= worst.back().score) return;
  worst.push_back(std::move(k));
  std::sort(worst.begin(), worst.end(), [](const Kept& a, const Kept& b) { return a.score > b.score; });
  if (worst.size() > kWorstFrames) worst.pop_back();
}

// `scored[i]`: pose i's cell was baked with visibility and impostors (a
// package baked with --impostor-route has them on the route's cells only,
// and at a junction the runtime may take a neighbour); the far metrics are
// over those poses, the frame times and whole-frame metrics over all.
nlohmann::json modeSummary(const std::vector<Sample>& v, const std::vector<bool>& scored, bool reference,
                           uint64_t frame_px) {
  auto col = [&](double Sample::*f, bool only_scored) {
    std::vector<double> x;
    for (size_t i = 0; i < v.size(); ++i)
      if (!only_scored || scored[i]) x.push_back(v[i].*f);
    return x;
  };
  auto mx = [](const std::vector<double>& x) { return x.empty() ? 0.0 : *std::max_element(x.begin(), x.end()); };
  const auto holes = col(&Sample::holes, true), spur = col(&Sample::spurious, true);
  const auto vis = col(&Sample::vis_px, true), sil = col(&Sample::sil_px, true);
  std::vector<double> far_bad;
  size_t missing_poses = 0;
  for (size_t i = 0; i < v.size(); ++i) {
    if (!scored[i]) continue;
    if (double(v[i].far_px) >= kFarBadMinShare * double(frame_px)) far_bad.push_back(v[i].far_bad);
    missing_poses += !v[i].missing.empty();
  }
  return {{"frame_ms_p50", pct(col(&Sample::ms, false), 50)},
          {"frame_ms_p95", pct(col(&Sample::ms, false), 95)},
          {"triangles_p50", pct(col(&Sample::tris, false), 50)},
          {"ssim_p50", pct(col(&Sample::ssim, false), 50)},
          {"ssim_p5", pct(col(&Sample::ssim, false), 5)},
          {"psnr_p50", reference ? NAN : pct(col(&Sample::psnr, false), 50)},
          {"bad_pixels_p50", pct(col(&Sample::bad, false), 50)},
          {"far_bad_p50", pct(far_bad, 50)},
          {"far_bad_p95", pct(far_bad, 95)},
          {"far_bad_max", mx(far_bad)},
          {"far_bad_poses", far_bad.size()},
          {"holes_p95", pct(holes, 95)},
          {"holes_max", mx(holes)},
          {"spurious_p95", pct(spur, 95)},
          {"spurious_max", mx(spur)},
          {"missing_objects_poses", missing_poses},
          {"visibility_error_px_p95", pct(vis, 95)},
          {"visibility_error_px_p50", pct(vis, 50)},
          {"silhouette_distance_px_p95", pct(sil, 95)}};
}

class RouteBench {
 public:
  explicit RouteBench(const RouteBenchOpts& o) : o_(o) {}
  int run();

 private:
  void open();
  void measurePose(size_t i);
  Sample measureMode(size_t i, size_t m, uint32_t& cell);
  void writePictures(size_t i, size_t m, const Sample& s);
  nlohmann::json summary() const;
  void writeHtml(const nlohmann::json& j);
  void writeWorst(HtmlPage& page);
  // The bake made this cell's impostors, or it has none to make (no far
  // block in its PVS). A twin of a baked cell shares its PVS, not its impostors.
  bool baked(uint32_t cell) const {
    const auto& t = city_.cellTables();
    if (cell >= t.visibility.size() || t.visibility[cell].blocks.empty()) return false;
    if (!t.impostors[cell].layered.empty() || !t.impostors[cell].single.empty()) return true;
    const graph::StreetGraph& g = city_.graph();
    for (uint32_t b : t.visibility[cell].blocks)
      if (std::find(g.local_blocks.begin(cell), g.local_blocks.end(cell), b) == g.local_blocks.end(cell)) return false;
    return true;
  }

  const RouteBenchOpts& o_;
  int w_ = 0, h_ = 0;
  stream::City city_;
  std::vector<uint32_t> route_;
  std::vector<Pose> poses_;
  std::unique_ptr<blvd_runtime, void (*)(blvd_runtime*)> rt_{nullptr, blvd_runtime_destroy};
  blvd_runtime_info info_{};
  std::vector<std::vector<Sample>> samples_ = std::vector<std::vector<Sample>>(kNumModes);
  std::vector<uint8_t> ref_, img_, diff_;
  std::vector<uint32_t> ref_items_, items_;
  std::vector<Figure> figures_;
  std::vector<Kept> worst_;
  size_t picture_every_ = 1;
  size_t cell_mismatches_ = 0;  // frames of a pose whose cell differs from the reference's
};

void RouteBench::open() {
  parseSize(o_.size, w_, h_);
  const unsigned n = parseAutoRoute(o_.route);
  std::string err;
  const core::Status st = city_.open(o_.package, err);
  if (st != core::Status::Ok) throw core::Error(st, err);
  if (!city_.hasImpostors())
    throw core::Error(core::Status::Unsupported, o_.package + " has no impostors: bake it with --impostor both");
  route_ = graph::seededRoute(city_.graph(), {n, o_.seed});
  poses_ = o_.step > 0 ? samplePoses(city_.streets(), route_, o_.step) : visitPoses(city_.streets(), route_);
  blvd_runtime_desc desc{};
  desc.struct_size = sizeof desc;
  desc.package_path = o_.package.c_str();
  desc.width = uint32_t(w_);
  desc.height = uint32_t(h_);
  desc.impostor_texture = o_.impostor_texture == "etc2" ? BLVD_TEXTURE_ETC2 : BLVD_TEXTURE_RGBA8;
  blvd_runtime* rt = nullptr;
  check(blvd_runtime_create(&desc, &rt), nullptr, "create runtime");
  rt_.reset(rt);
  // The route lets the runtime follow it at junctions, as a navigating host's would.
  check(blvd_set_route(rt, route_.data(), route_.size()), rt, "route");
  info_.struct_size = sizeof info_;
  check(blvd_runtime_get_info(rt, &info_), rt, "info");
  const size_t px = size_t(w_) * h_;
  ref_.resize(px * 4), img_.resize(px * 4), diff_.resize(px * 4);
  ref_items_.resize(px), items_.resize(px);
  picture_every_ = std::max<size_t>(1, poses_.size() / std::max(1, o_.pictures));
  if (!o_.html_dir.empty()) {
    ::mkdir(o_.html_dir.c_str(), 0755);
    ::mkdir((o_.html_dir + "/frames").c_str(), 0755);
  }
}

// One mode at pose i: timed frames, then its pixels and object ids. The full
// model (m == 0) is the reference the others are measured against; `cell`
// is the runtime's cell for the pose, taken from the reference frame.
Sample RouteBench::measureMode(size_t i, size_t m, uint32_t& cell) {
  blvd_runtime* rt = rt_.get();
  check(blvd_set_render_mode(rt, kModes[m].mode, kModes[m].radius), rt, "mode");
  blvd_frame_stats fs{};
  fs.struct_size = sizeof fs;
  // The cell is made resident first (streaming is measured by `blvd bench
  // budget` and `memory`), one untimed frame warms up, then the timed ones.
  check(blvd_wait_resident(rt, 60000), rt, "wait for the cell");
  check(blvd_render(rt, &fs), rt, "render");
  std::vector<double> ms;
  for (int r = 0; r < o_.repeat; ++r) {
    check(blvd_render(rt, &fs), rt, "render");
    ms.push_back(fs.frame_ms);
  }
  auto& px = m == 0 ? ref_ : img_;
  check(blvd_read_pixels(rt, px.data(), px.size()), rt, "read pixels");
  check(blvd_read_items(rt, (m == 0 ? ref_items_ : items_).data(), items_.size()), rt, "read items");
  Sample s;
  s.ms = pct(ms, 50);
  s.tris = double(fs.triangles);
  s.cell = fs.cell;
  if (m != 0 && fs.cell != cell) ++cell_mismatches_;
  if (m == 0) {
    cell = fs.cell;
    return s;
  }
  const imaging::ImageMetrics q = imaging::compareImages(ref_.data(), img_.data(), w_, h_);
  s.ssim = q.ssim, s.psnr = q.psnr, s.bad = q.bad_pixels;
  FarInputs in = farInputs(city_, cell, kModes[m].mode);
  in.w = w_, in.h = h_;
  in.ref_rgba = ref_.data(), in.test_rgba = img_.data();
  in.ref_items = ref_items_.data(), in.test_items = items_.data();
  FarMetrics f = measureFar(in);
  s.far_bad = f.far_bad, s.holes = f.holes, s.spurious = f.spurious;
  s.vis_px = f.visibility_error_px, s.sil_px = f.silhouette_distance_px, s.missing = f.missing_shown, s.far_px = f.far_px;
  if (m == kBlvd && !o_.html_dir.empty() && baked(fs.cell)) {
    Kept k;
    k.pose = i;
    const bool counts = double(f.far_px) >= kFarBadMinShare * double(w_) * double(h_);
    k.score = (counts ? f.far_bad : 0.0) + f.spurious;
    if (worst_.size() < kWorstFrames || k.score > worst_.back().score) {
      k.full = ref_, k.blvd = img_, k.missing = f.missing;
      k.overlay.resize(ref_.size());
      farOverlay(ref_.data(), f, w_, h_, k.overlay.data());
      keepWorst(worst_, std::move(k));
    }
  }
  return s;
}

void RouteBench::writePictures(size_t i, size_t m, const Sample& s) {
  if (o_.html_dir.empty() || i % picture_every_ != 0 || !(m == 0 || m == kBlvd)) return;
  std::string err;
  char name[96];
  std::snprintf(name, sizeof name, "frames/pose%04zu_%s.png", i, kModes[m].key);
  if (!imaging::writePng(o_.html_dir + "/" + name, w_, h_, (m == 0 ? ref_ : img_).data(), err))
    throw core::Error(core::Status::Io, err);
  figures_.push_back({name, std::string(kModes[m].key) + ", pose " + std::to_string(i) + ", cell " +
                                std::to_string(poses_[i].cell) + ": " + std::to_string(int(s.ms)) + " ms" +
                                (m ? ", SSIM " + fmt(s.ssim, 3) : "")});
  if (m == 0) return;
  imaging::diffImage(ref_.data(), img_.data(), w_, h_, diff_.data());
  std::snprintf(name, sizeof name, "frames/pose%04zu_diff.png", i);
  if (!imaging::writePng(o_.html_dir + "/" + name, w_, h_, diff_.data(), err)) throw core::Error(core::Status::Io, err);
  figures_.push_back({name, "difference (red: off by more than 10 %), bad " + fmt(100 * s.bad, 2) + " %"});
}

void RouteBench::measurePose(size_t i) {
  const Pose& p = poses_[i];
  check(blvd_set_pose_local(rt_.get(), p.x, p.y, float(p.heading_deg), 0.f), rt_.get(), "pose");
  uint32_t cell = p.cell;
  for (size_t m = 0; m < kNumModes; ++m) {
    const Sample s = measureMode(i, m, cell);
    samples_[m].push_back(s);
    writePictures(i, m, s);
  }
}

nlohmann::json RouteBench::summary() const {
  nlohmann::json j;
  j["package"] = o_.package;
  j["route"] = {{"spec", o_.route}, {"seed", o_.seed}, {"cells", route_.size()}, {"poses", poses_.size()}};
  j["size"] = {w_, h_};
  j["backend"] = info_.backend;
  j["gl_renderer"] = info_.gl_renderer;
  j["full_model_triangles"] = info_.triangle_count;
  j["far_definitions"] = {{"far_bad", "share of the far region"},
                          {"holes", "share of the frame"},
                          {"spurious", "share of the frame"},
                          {"edge_tolerance_px", FarInputs{}.edge_tolerance_px},
                          {"far_bad_min_far_share", kFarBadMinShare},
                          {"visibility_error_px", "95th percentile per pose of the thickness of wrong far visibility at the silhouettes"},
                          {"silhouette_distance_px", "95th percentile per pose of the far silhouettes' distance to the "
                                                     "other image's"}};
  std::vector<bool> scored(poses_.size());
  size_t n_scored = 0;
  for (size_t i = 0; i < poses_.size(); ++i) n_scored += scored[i] = baked(samples_[kBlvd][i].cell);
  j["far_scored_poses"] = n_scored;
  j["impostor_texture"] = o_.impostor_texture;
  for (size_t m = 0; m < kNumModes; ++m)
    j["modes"][kModes[m].key] = modeSummary(samples_[m], scored, m == 0, uint64_t(w_) * uint64_t(h_));
  const double full50 = j["modes"]["full"]["frame_ms_p50"], blvd50 = j["modes"]["blvd"]["frame_ms_p50"];
  j["speedup_p50"] = blvd50 > 0 ? full50 / blvd50 : NAN;
  j["triangle_ratio_p50"] =
      double(j["modes"]["blvd"]["triangles_p50"]) / std::max(1.0, double(j["modes"]["full"]["triangles_p50"]));
  nlohmann::json worst = nlohmann::json::array();
  for (const Kept& k : worst_)
    worst.push_back({{"pose", k.pose},
                     {"cell", samples_[kBlvd][k.pose].cell},
                     {"score", k.score},
                     {"far_bad", samples_[kBlvd][k.pose].far_bad},
                     {"spurious", samples_[kBlvd][k.pose].spurious},
                     {"missing_blocks", k.missing}});
  j["worst_blvd_poses"] = worst;
  // Per pose, blvd's far metrics (and single's beside them): where the
  // route's figures come from.
  nlohmann::json per = nlohmann::json::array();
  size_t off_route = 0, bare = 0;  // poses on another cell than the route's; on a cell not baked
  for (size_t i = 0; i < poses_.size(); ++i) {
    const Sample& s = samples_[kBlvd][i];
    const bool has = baked(s.cell);
    off_route += s.cell != poses_[i].cell;
    bare += !has;
    double lat = 0, lon = 0, hgt = 0;
    city_.frame().reverse({poses_[i].x, poses_[i].y, 0.0}, lat, lon, hgt);
    nlohmann::json shown = nlohmann::json::array();
    for (const MissingObject& o : s.missing)
      shown.push_back({{"block", o.block}, {"px", o.px}, {"own", o.own}, {"other_layer", o.other_layer},
                       {"geometry", o.geometry}, {"nothing", o.nothing},
                       {"bad", o.bad}});
    per.push_back({{"lat", lat}, {"lon", lon}, {"heading", poses_[i].heading_deg},
                   {"route_cell", poses_[i].cell}, {"cell", s.cell}, {"baked", has}, {"far_px", s.far_px},
                   {"far_bad", s.far_bad}, {"holes", s.holes}, {"spurious", s.spurious},
                   {"visibility_error_px", s.vis_px}, {"silhouette_distance_px", s.sil_px}, {"missing_objects", s.missing.size()},
                   {"missing", shown},
                   {"single", {{"far_bad", samples_[kSingle][i].far_bad},
                               {"visibility_error_px", samples_[kSingle][i].vis_px},
                               {"missing_objects", samples_[kSingle][i].missing.size()}}}});
  }
  j["blvd_poses"] = per;
  j["poses_off_route_cell"] = off_route;
  j["poses_not_baked"] = bare;
  j["cell_mismatches"] = cell_mismatches_;
  return j;
}

void RouteBench::writeWorst(HtmlPage& page) {
  page.h2("worst frames: full | blvd | far error (blue: far city, red: wrong or missing, magenta: spurious)");
  std::vector<Figure> figs;
  std::string err;
  for (const Kept& k : worst_) {
    const Pose& p = poses_[k.pose];
    const char* kinds[3] = {"full", "blvd", "far"};
    const std::vector<uint8_t>* imgs[3] = {&k.full, &k.blvd, &k.overlay};
    for (int c = 0; c < 3; ++c) {
      char name[96];
      std::snprintf(name, sizeof name, "frames/worst%04zu_%s.png", k.pose, kinds[c]);
      if (!imaging::writePng(o_.html_dir + "/" + name, w_, h_, imgs[c]->data(), err))
        throw core::Error(core::Status::Io, err);
      const Sample& s = samples_[kBlvd][k.pose];
      std::string cap;
      if (c == 0) cap = "pose " + std::to_string(k.pose) + ", cell " + std::to_string(s.cell) + ": " +
                        viewCommand(o_, city_, p, "full");
      if (c == 1) cap = viewCommand(o_, city_, p, "blvd");
      if (c == 2)
        cap = "far_bad " + fmt(100 * s.far_bad, 1) + " % of the far region, spurious " + fmt(100 * s.spurious, 2) +
              " %, holes " + fmt(100 * s.holes, 2) + " % of the frame, visibility error " + fmt(s.vis_px, 1) +
              " px, missing objects " + std::to_string(s.missing.size());
      figs.push_back({name, cap});
    }
  }
  page.imageGrid(figs, 3);
}

void RouteBench::writeHtml(const nlohmann::json& j) {
  PlotSpec ft, ss, fb;
  ft.title = "Frame time along the route", ft.x_label = "pose", ft.y_label = "ms";
  ss.title = "SSIM against the full model", ss.x_label = "pose", ss.y_label = "SSIM";
  fb.title = "Far region wrong (far_bad) along the route", fb.x_label = "pose", fb.y_label = "share of the far region";
  for (size_t m = 0; m < kNumModes; ++m) {
    Series a{kModes[m].key, {}, ""}, b = a, c = a;
    for (const Sample& s : samples_[m]) a.y.push_back(s.ms), b.y.push_back(s.ssim), c.y.push_back(s.far_bad);
    ft.series.push_back(a);
    if (m) ss.series.push_back(b), fb.series.push_back(c);
  }
  HtmlPage page("blvd bench route: " + o_.package);
  page.paragraph(std::to_string(route_.size()) + " cells, " + std::to_string(poses_.size()) + " poses, " + o_.size +
                 " on " + info_.backend + " (" + info_.gl_renderer + "). Map data © OpenStreetMap contributors (ODbL).");
  std::vector<std::vector<std::string>> rows = {{"mode", "frame ms p50", "p95", "triangles p50", "SSIM p50", "bad px p50",
                                                 "far_bad p50", "p95", "holes p95", "spurious p95", "max",
                                                 "missing-object poses", "visibility error px p95",
                                                 "silhouette distance px p95"}};
  for (size_t m = 0; m < kNumModes; ++m) {
    const auto& q = j["modes"][kModes[m].key];
    auto pc = [&](const char* k, int d) { return fmt(100 * double(q[k]), d) + " %"; };
    rows.push_back({kModes[m].key, fmt(q["frame_ms_p50"], 1), fmt(q["frame_ms_p95"], 1), fmt(q["triangles_p50"], 0),
                    fmt(q["ssim_p50"], 3), pc("bad_pixels_p50", 2), pc("far_bad_p50", 1), pc("far_bad_p95", 1),
                    pc("holes_p95", 2), pc("spurious_p95", 3), pc("spurious_max", 2),
                    std::to_string(int(q["missing_objects_poses"])), fmt(q["visibility_error_px_p95"], 1),
                    fmt(q["silhouette_distance_px_p95"], 1)});
  }
  page.table(rows);
  page.paragraph("speed-up (full / blvd, median frame time): " + fmt(j["speedup_p50"], 2) +
                 ". far_bad is a share of the far region (pixels where the full model shows a block that is not "
                 "local); holes and spurious are shares of the frame.");
  page.raw(svgLinePlot(ft));
  page.raw(svgLinePlot(ss));
  page.raw(svgLinePlot(fb));
  writeWorst(page);
  page.h2("full | blvd | difference");
  page.imageGrid(figures_, 3);
  std::string err;
  if (!page.write(o_.html_dir + "/index.html", err)) throw core::Error(core::Status::Io, err);
}

int RouteBench::run() {
  open();
  for (size_t i = 0; i < poses_.size(); ++i) {
    measurePose(i);
    std::fprintf(stderr, "\r  pose %zu/%zu", i + 1, poses_.size());
  }
  std::fprintf(stderr, "\n");
  const nlohmann::json j = summary();
  writeText(o_.json_path, j.dump(2));
  std::printf("%s\n", j.dump(2).c_str());
  if (!o_.html_dir.empty()) writeHtml(j);
  return 0;
}

}  // namespace

int runRouteBench(const RouteBenchOpts& o) { return RouteBench(o).run(); }

}  // namespace blvd::cli
