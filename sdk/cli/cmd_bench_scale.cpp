// `blvd bench scale PKG...`: frame cost and memory against city size. The
// same route is driven on each package (a city and the same city tiled by
// `blvd bake --tile 2x2`, `4x4`: 4 and 16 copies side by side, tile 0 the
// original) in a fresh child process each, the packages taking turns for
// `--rounds` rounds (medians kept):
// peak RSS, table and GPU bytes, and the blvd and full-model frame times and
// triangles of every pose. blvd's cost should stay flat while the full
// model's grows with what it sees. `--html DIR` plots both against the size.
//
// What a tiled city stands for: more cells, blocks and blobs in the package
// (its tables, the PVS reach of far copies), the same streets repeated with
// gaps between tiles; not a denser or taller city.
#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "cli/bench_util.h"
#include "cli/commands.h"
#include "cli/drive_child.h"
#include "cli/report.h"
#include "cli/route.h"
#include "stream/city.h"

namespace blvd::cli {
namespace {

struct ScaleOpts {
  std::vector<std::string> packages;
  MemoryOpts drive;
  std::string json_path, html_dir;
  double max_blvd_ms_pct = 5.0, max_rss_pct = 1.0;  // the goals, against the first package
  int rounds = 3;  // each package driven this often, taking turns; medians kept
};

double num(const nlohmann::json& j, const char* a, const char* b = nullptr) {
  const nlohmann::json& v = b ? j.at(a).at(b) : j.at(a);
  return v.is_number() ? v.get<double>() : NAN;
}

// One package's rounds as one run: the medians of the times and of the peak.
nlohmann::json mergeRounds(const std::vector<nlohmann::json>& rounds) {
  nlohmann::json r = rounds.front();
  const auto median = [&](const char* a, const char* b) {
    std::vector<double> v;
    for (const auto& x : rounds) v.push_back(num(x, a, b));
    return pct(v, 50);
  };
  for (const char* mode : {"blvd", "full"})
    for (const char* k : {"frame_ms_p50", "frame_ms_p95"}) r[mode][k] = median(mode, k);
  std::vector<double> peaks;
  for (const auto& x : rounds) peaks.push_back(num(x, "rss_peak"));
  r["rss_peak"] = pct(peaks, 50);
  r["rounds"] = rounds.size();
  return r;
}

void writePlots(const ScaleOpts& o, const nlohmann::json& runs) {
  PlotSpec ms, rss;
  ms.title = "Frame time p50 against city size", ms.x_label = "copies of the city", ms.y_label = "ms";
  rss.title = "Peak resident memory against city size", rss.x_label = "copies of the city", rss.y_label = "MiB";
  Series full{"full model", {}, ""}, blvd{"blvd", {}, ""}, peak{"blvd peak RSS", {}, ""};
  for (const auto& r : runs) {
    ms.x.push_back(num(r, "copies"));
    rss.x.push_back(num(r, "copies"));
    full.y.push_back(num(r, "full", "frame_ms_p50"));
    blvd.y.push_back(num(r, "blvd", "frame_ms_p50"));
    peak.y.push_back(num(r, "rss_peak") / (1024.0 * 1024.0));
  }
  ms.series = {full, blvd};
  rss.series = {peak};
  rss.y_min = 0;
  HtmlPage page("blvd bench scale");
  page.paragraph("The same route on each package, a child process each. A tiled city repeats the same streets "
                 "with gaps between tiles: it stands for a package with more cells and blocks, not a denser city. "
                 "Map data © OpenStreetMap contributors (ODbL).");
  page.raw(svgLinePlot(ms));
  page.raw(svgLinePlot(rss));
  std::string err;
  ::mkdir(o.html_dir.c_str(), 0755);
  if (!page.write(o.html_dir + "/index.html", err)) throw core::Error(core::Status::Io, err);
}

int runScale(const ScaleOpts& o) {
  const unsigned n = parseAutoRoute(o.drive.route);
  stream::City first;
  std::string err;
  if (const core::Status st = first.open(o.packages[0], err, stream::City::Tables::Graph); st != core::Status::Ok)
    throw core::Error(st, err);
  const std::vector<uint32_t> route = graph::seededRoute(first.graph(), {n, o.drive.seed});
  const std::string cells = cellList(route), exe = selfExe();
  std::vector<size_t> cell_counts;
  for (const std::string& pkg : o.packages) {
    stream::City c;
    if (const core::Status st = c.open(pkg, err, stream::City::Tables::Graph); st != core::Status::Ok)
      throw core::Error(st, err);
    checkSameRoute(first, c, route);
    cell_counts.push_back(c.graph().cellCount());
  }
  // The packages take turns, round after round, in alternating order (first
  // to last, then last to first), so that the shared machine's drifting speed
  // and what one process leaves warm for the next reach them alike.
  std::vector<std::vector<nlohmann::json>> rounds(o.packages.size());
  for (int k = 0; k < o.rounds; ++k)
    for (size_t j = 0; j < o.packages.size(); ++j) {
      const size_t i = k % 2 == 0 ? j : o.packages.size() - 1 - j;
      std::fprintf(stderr, "bench scale: round %d, %s (%zu cells) ...\n", k + 1, o.packages[i].c_str(), cell_counts[i]);
      rounds[i].push_back(driveChild(exe, o.packages[i], cells, o.drive));
    }
  nlohmann::json runs = nlohmann::json::array();
  for (size_t i = 0; i < o.packages.size(); ++i) {
    nlohmann::json r = mergeRounds(rounds[i]);
    r["package"] = o.packages[i];
    r["cells"] = cell_counts[i];
    r["copies"] = double(cell_counts[i]) / double(cell_counts[0]);
    r["speedup_p50"] = num(r, "full", "frame_ms_p50") / num(r, "blvd", "frame_ms_p50");
    runs.push_back(r);
  }
  const nlohmann::json &a = runs.front(), &z = runs.back();
  nlohmann::json j;
  j["route"] = route;
  j["runs"] = runs;
  j["blvd_ms_p50_change_pct"] = 100.0 * (num(z, "blvd", "frame_ms_p50") / num(a, "blvd", "frame_ms_p50") - 1);
  j["full_ms_p50_change_pct"] = 100.0 * (num(z, "full", "frame_ms_p50") / num(a, "full", "frame_ms_p50") - 1);
  j["rss_peak_change_pct"] = 100.0 * (num(z, "rss_peak") / num(a, "rss_peak") - 1);
  j["checks"] = {{"blvd_ms_within", std::fabs(j["blvd_ms_p50_change_pct"].get<double>()) <= o.max_blvd_ms_pct},
                 {"rss_within", std::fabs(j["rss_peak_change_pct"].get<double>()) <= o.max_rss_pct}};
  const std::string text = j.dump(2);
  std::printf("%s\n", text.c_str());
  writeText(o.json_path, text);
  if (!o.html_dir.empty()) writePlots(o, runs);
  return 0;
}

}  // namespace

void addBenchScale(CLI::App& bench, Runner& run) {
  auto o = std::make_shared<ScaleOpts>();
  o->drive.laps = 2;
  o->drive.frame_repeat = 3;
  auto* s = bench.add_subcommand("scale", "frame time and memory of blvd and the full model against city size");
  s->add_option("packages", o->packages, "the city, then larger ones (blvd bake --tile 2x2, 4x4)")
      ->required()
      ->expected(2, 16)
      ->check(CLI::ExistingFile);
  s->add_option("--route", o->drive.route, "auto:N cells of the first package, driven on each")->capture_default_str();
  s->add_option("--seed", o->drive.seed)->capture_default_str();
  s->add_option("--step", o->drive.step, "metres between poses")->capture_default_str();
  s->add_option("--laps", o->drive.laps, "laps before the timed frames; the first warms up")
      ->capture_default_str()
      ->check(CLI::Range(2, 100));
  s->add_option("--repeat", o->drive.frame_repeat, "timed frames a pose and mode (their median counts)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
  s->add_option("--rounds", o->rounds, "drives of each package, taking turns (medians kept)")
      ->capture_default_str()
      ->check(CLI::Range(1, 20));
  s->add_option("--size", o->drive.size)->capture_default_str();
  s->add_option("--json", o->json_path, "write the JSON here too");
  s->add_option("--html", o->html_dir, "write plots against city size here (index.html)");
  s->callback([o, &run] { run = [o] { return runScale(*o); }; });
}

}  // namespace blvd::cli
