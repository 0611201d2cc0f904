// `blvd bench`: its subcommands (route here, the others in cmd_bench_*.cpp).
#include <memory>

#include "cli/bench_route.h"
#include "cli/commands.h"

namespace blvd::cli {

void addBench(CLI::App& app, Runner& run) {
  auto* bench = app.add_subcommand("bench", "benchmarks that report ratios measured side by side in one run");
  bench->require_subcommand(1);
  auto o = std::make_shared<RouteBenchOpts>();
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
  r->add_option("--impostor-texture", o->impostor_texture, "how cell slots hold impostor images: rgba8 or etc2")
      ->capture_default_str()
      ->check(CLI::IsMember({"rgba8", "etc2"}));
  r->callback([o, &run] { run = [o] { return runRouteBench(*o); }; });
  addBenchMemory(*bench, run);
  addBenchBudget(*bench, run);
  addBenchScale(*bench, run);
  addBenchDecode(*bench, run);
  addBenchStream(*bench, run);
#ifdef BLVD_HAVE_BENCH_TRACK
  addBenchTrack(*bench, run);
#endif
}

}  // namespace blvd::cli
