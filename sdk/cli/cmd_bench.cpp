// `blvd bench route`: drives the camera along a path of connected cells and
// renders every pose in every mode side by side in one run, so the reported
// figures are ratios on one machine (full model vs blvd, and the baselines),
// plus fidelity against the full model's image of the same pose.
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <vector>

#include <nlohmann/json.hpp>

#include "blvd/blvd.h"
#include "cli/bench_util.h"
#include "cli/commands.h"
#include "cli/report.h"
#include "cli/route.h"
#include "core/status.h"
#include "render/image.h"
#include "render/metrics.h"
#include "stream/city.h"

namespace blvd::cli {
namespace {

struct BenchOpts {
  std::string package, route = "auto:200", size = "800x480", json_path, html_dir, backend = "auto";
  uint64_t seed = 1;
  double step = 0;  // metres between poses; 0: one pose per cell (its middle)
  int repeat = 1;   // timed renders per pose and mode (median kept)
  int pictures = 24;
};

struct Mode {
  const char* key;
  blvd_render_mode mode;
  float radius;
};
const Mode kModes[] = {{"full", BLVD_MODE_FULL, 0},       {"local", BLVD_MODE_LOCAL, 0},
                       {"radius100", BLVD_MODE_RADIUS, 100}, {"radius250", BLVD_MODE_RADIUS, 250},
                       {"single", BLVD_MODE_SINGLE, 0},   {"blvd", BLVD_MODE_BLVD, 0}};
constexpr size_t kNumModes = sizeof kModes / sizeof kModes[0];

int runRoute(const BenchOpts& o) {
  int w = 0, h = 0;
  parseSize(o.size, w, h);
  const unsigned n = parseAutoRoute(o.route);
  stream::City city;
  std::string err;
  const core::Status st = city.open(o.package, err);
  if (st != core::Status::Ok) throw core::Error(st, err);
  if (!city.hasImpostors())
    throw core::Error(core::Status::Unsupported, o.package + " has no impostors: bake it with --impostor both");
  const auto route = autoRoute(city.graph(), n, o.seed);
  std::vector<Pose> poses;
  if (o.step > 0) {
    poses = samplePoses(city.graph(), route, o.step);
  } else {
    // One pose per cell, halfway along it.
    const auto all = samplePoses(city.graph(), route, 1.0);
    for (uint32_t c : route) {
      std::vector<const Pose*> on;
      for (const Pose& p : all)
        if (p.cell == c) on.push_back(&p);
      if (!on.empty()) poses.push_back(*on[on.size() / 2]);
    }
  }

  blvd_runtime_desc desc{};
  desc.struct_size = sizeof desc;
  desc.package_path = o.package.c_str();
  desc.width = uint32_t(w);
  desc.height = uint32_t(h);
  blvd_runtime* rt = nullptr;
  check(blvd_runtime_create(&desc, &rt), nullptr, "create runtime");
  std::unique_ptr<blvd_runtime, void (*)(blvd_runtime*)> guard(rt, blvd_runtime_destroy);
  blvd_runtime_info info{};
  info.struct_size = sizeof info;
  check(blvd_runtime_get_info(rt, &info), rt, "info");

  struct Sample {
    double ms, tris, ssim, psnr, bad;
  };
  std::vector<std::vector<Sample>> samples(kNumModes);
  std::vector<uint8_t> ref(size_t(w) * h * 4), img(ref.size()), diff(ref.size());
  std::vector<uint32_t> pose_cells;
  const bool html = !o.html_dir.empty();
  if (html) {
    ::mkdir(o.html_dir.c_str(), 0755);
    ::mkdir((o.html_dir + "/frames").c_str(), 0755);
  }
  std::vector<Figure> figures;
  const size_t picture_every = std::max<size_t>(1, poses.size() / std::max(1, o.pictures));
  for (size_t i = 0; i < poses.size(); ++i) {
    const Pose& p = poses[i];
    check(blvd_set_pose_local(rt, p.x, p.y, float(p.heading_deg), 0.f), rt, "pose");
    for (size_t m = 0; m < kNumModes; ++m) {
      check(blvd_set_render_mode(rt, kModes[m].mode, kModes[m].radius), rt, "mode");
      blvd_frame_stats fs{};
      fs.struct_size = sizeof fs;
      // The cell is made resident first (streaming is measured by `blvd bench
      // budget` and `memory`), one untimed frame warms up, then the timed ones.
      check(blvd_wait_resident(rt, 60000), rt, "wait for the cell");
      check(blvd_render(rt, &fs), rt, "render");
      std::vector<double> ms;
      for (int r = 0; r < o.repeat; ++r) {
        check(blvd_render(rt, &fs), rt, "render");
        ms.push_back(fs.frame_ms);
      }
      check(blvd_read_pixels(rt, (m == 0 ? ref : img).data(), ref.size()), rt, "read pixels");
      Sample s{pct(ms, 50), double(fs.triangles), 1.0, INFINITY, 0.0};
      if (m > 0) {
        const render::ImageMetrics q = render::compareImages(ref.data(), img.data(), w, h);
        s.ssim = q.ssim;
        s.psnr = q.psnr;
        s.bad = q.bad_pixels;
      }
      samples[m].push_back(s);
      if (html && i % picture_every == 0 && (m == 0 || std::string(kModes[m].key) == "blvd")) {
        char name[96];
        std::snprintf(name, sizeof name, "frames/pose%04zu_%s.png", i, kModes[m].key);
        if (!render::writePng(o.html_dir + "/" + name, w, h, (m == 0 ? ref : img).data(), err))
          throw core::Error(core::Status::Io, err);
        figures.push_back({name, std::string(kModes[m].key) + ", pose " + std::to_string(i) + ", cell " +
                                     std::to_string(p.cell) + ": " + std::to_string(int(s.ms)) + " ms" +
                                     (m ? ", SSIM " + std::to_string(s.ssim).substr(0, 5) : "")});
        if (m > 0) {
          render::diffImage(ref.data(), img.data(), w, h, diff.data());
          std::snprintf(name, sizeof name, "frames/pose%04zu_diff.png", i);
          if (!render::writePng(o.html_dir + "/" + name, w, h, diff.data(), err)) throw core::Error(core::Status::Io, err);
          figures.push_back({name, "difference (red: off by more than 10 %), bad " +
                                       std::to_string(100 * s.bad).substr(0, 4) + " %"});
        }
      }
    }
    pose_cells.push_back(p.cell);
    std::fprintf(stderr, "\r  pose %zu/%zu", i + 1, poses.size());
  }
  std::fprintf(stderr, "\n");

  nlohmann::json j;
  j["package"] = o.package;
  j["route"] = {{"spec", o.route}, {"seed", o.seed}, {"cells", route.size()}, {"poses", poses.size()}};
  j["size"] = {w, h};
  j["backend"] = info.backend;
  j["gl_renderer"] = info.gl_renderer;
  j["full_model_triangles"] = info.triangle_count;
  for (size_t m = 0; m < kNumModes; ++m) {
    std::vector<double> ms, tris, ssim, psnr, bad;
    for (const Sample& s : samples[m]) {
      ms.push_back(s.ms);
      tris.push_back(s.tris);
      ssim.push_back(s.ssim);
      psnr.push_back(s.psnr);
      bad.push_back(s.bad);
    }
    j["modes"][kModes[m].key] = {{"frame_ms_p50", pct(ms, 50)}, {"frame_ms_p95", pct(ms, 95)},
                                 {"triangles_p50", pct(tris, 50)}, {"ssim_p50", pct(ssim, 50)},
                                 {"ssim_p5", pct(ssim, 5)},       {"psnr_p50", m ? pct(psnr, 50) : NAN},
                                 {"bad_pixels_p50", pct(bad, 50)}};
  }
  const double full50 = j["modes"]["full"]["frame_ms_p50"], blvd50 = j["modes"]["blvd"]["frame_ms_p50"];
  j["speedup_p50"] = blvd50 > 0 ? full50 / blvd50 : NAN;
  j["triangle_ratio_p50"] =
      double(j["modes"]["blvd"]["triangles_p50"]) / std::max(1.0, double(j["modes"]["full"]["triangles_p50"]));
  const std::string text = j.dump(2);
  if (!o.json_path.empty()) {
    std::ofstream f(o.json_path);
    if (!(f << text << "\n")) throw core::Error(core::Status::Io, o.json_path + ": cannot write");
  }
  std::printf("%s\n", text.c_str());

  if (html) {
    PlotSpec ft;
    ft.title = "Frame time along the route";
    ft.x_label = "pose";
    ft.y_label = "ms";
    PlotSpec ss;
    ss.title = "SSIM against the full model";
    ss.x_label = "pose";
    ss.y_label = "SSIM";
    for (size_t m = 0; m < kNumModes; ++m) {
      Series a{kModes[m].key, {}, ""}, b{kModes[m].key, {}, ""};
      for (const Sample& s : samples[m]) a.y.push_back(s.ms), b.y.push_back(s.ssim);
      ft.series.push_back(a);
      if (m) ss.series.push_back(b);
    }
    HtmlPage page("blvd bench route: " + o.package);
    page.paragraph(std::to_string(route.size()) + " cells, " + std::to_string(poses.size()) + " poses, " + o.size +
                   " on " + info.backend + " (" + info.gl_renderer + "). Map data © OpenStreetMap contributors (ODbL).");
    std::vector<std::vector<std::string>> rows = {
        {"mode", "frame ms p50", "frame ms p95", "triangles p50", "SSIM p50", "SSIM p5", "PSNR p50", "bad px p50"}};
    for (size_t m = 0; m < kNumModes; ++m) {
      const auto& q = j["modes"][kModes[m].key];
      auto f = [](double v, int d) {
        char b[32];
        std::snprintf(b, sizeof b, "%.*f", d, v);
        return std::string(b);
      };
      rows.push_back({kModes[m].key, f(q["frame_ms_p50"], 1), f(q["frame_ms_p95"], 1), f(q["triangles_p50"], 0),
                      f(q["ssim_p50"], 3), f(q["ssim_p5"], 3), m ? f(q["psnr_p50"], 1) : "-",
                      f(100 * double(q["bad_pixels_p50"]), 2) + " %"});
    }
    page.table(rows);
    page.paragraph("speed-up (full / blvd, median frame time): " + std::to_string(double(j["speedup_p50"])));
    page.raw(svgLinePlot(ft));
    page.raw(svgLinePlot(ss));
    page.h2("full | blvd | difference");
    page.imageGrid(figures, 3);
    if (!page.write(o.html_dir + "/index.html", err)) throw core::Error(core::Status::Io, err);
  }
  return 0;
}

}  // namespace

void addBench(CLI::App& app, Runner& run) {
  auto* bench = app.add_subcommand("bench", "benchmarks that report ratios measured side by side in one run");
  bench->require_subcommand(1);
  auto o = std::make_shared<BenchOpts>();
  auto* r = bench->add_subcommand("route", "drive a route; every pose in every mode; speed and fidelity vs full");
  r->add_option("package", o->package)->required()->check(CLI::ExistingFile);
  r->add_option("--route", o->route, "auto:N (N connected cells from --seed)")->capture_default_str();
  r->add_option("--seed", o->seed)->capture_default_str();
  r->add_option("--step", o->step, "metres between poses (0: one per cell)")->capture_default_str();
  r->add_option("--repeat", o->repeat, "timed frames per pose and mode")->capture_default_str()->check(CLI::Range(1, 100));
  r->add_option("--size", o->size)->capture_default_str();
  r->add_option("--json", o->json_path, "write the JSON here too");
  r->add_option("--html", o->html_dir, "write an HTML page with frames and SVG plots into this folder");
  r->add_option("--pictures", o->pictures, "poses shown in the HTML page")->capture_default_str();
  r->callback([o, &run] { run = [o] { return runRoute(*o); }; });
  addBenchMemory(*bench, run);
  addBenchBudget(*bench, run);
  addBenchDecode(*bench, run);
#ifdef BLVD_HAVE_BENCH_TRACK
  addBenchTrack(*bench, run);
#endif
}

}  // namespace blvd::cli
