#include <cstdio>

#include "bake/bake.h"
#include "cli/bake_report.h"
#include "cli/commands.h"
#include "cli/route.h"
#include "core/status.h"

namespace blvd::cli {

void addBake(CLI::App& app, Runner& run) {
  auto* cmd = app.add_subcommand("bake", "bake an OpenStreetMap .osm.pbf into a .blvd package");
  struct Opts {
    std::string in, out, report_dir;
    bake::BakeOptions bake;
    bool no_draco = false;
    std::string impostor = "layered", only_route;
    uint64_t seed = 1;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("input", o->in, "OpenStreetMap extract (.osm.pbf)")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", o->out, "package to write (.blvd)")->required();
  cmd->add_option("--default-height", o->bake.osm.default_height_m,
                  "height of buildings without height or building:levels tags, metres")
      ->capture_default_str()->check(CLI::Range(1.0, 500.0));
  cmd->add_option("--level-height", o->bake.osm.level_height_m, "metres per building:levels level")
      ->capture_default_str()->check(CLI::Range(1.0, 10.0));
  cmd->add_flag("--quiet", o->bake.quiet, "plain log lines, no progress bar");
  cmd->add_flag("--no-draco", o->no_draco, "store plain GLB buffers instead of Draco-compressed meshes");
  cmd->add_option("--impostor", o->impostor,
                  "impostors per cell: layered (Decoret 99 MMI), single (Sillion 97), both, or none")
      ->capture_default_str()->check(CLI::IsMember({"layered", "single", "both", "none"}));
  cmd->add_option("--texture", o->bake.impostor.texture_max, "largest impostor texture side, pixels")
      ->capture_default_str()->check(CLI::Range(32, 4096));
  cmd->add_option("--threshold-px", o->bake.impostor.threshold_px,
                  "layer threshold T in pixels at the display (Decoret 99 section 4.2)")
      ->capture_default_str()->check(CLI::Range(0.5, 500.0));
  cmd->add_option("--max-layers", o->bake.impostor.max_layers, "most impostor layers per cell (extra layers merge)")
      ->capture_default_str()->check(CLI::Range(1, 64));
  cmd->add_option("--landmark-height", o->bake.impostor.landmark_height_m,
                  "blocks with a building at least this tall are landmarks (metres)")
      ->capture_default_str()->check(CLI::Range(1.0, 1000.0));
  cmd->add_option("--landmark-scale", o->bake.impostor.landmark_scale,
                  "factor on a landmark's layer weights (Decoret 99 section 4.2)")
      ->capture_default_str()->check(CLI::Range(1.0, 100.0));
  cmd->add_option("--grid", o->bake.impostor.grid_px, "impostor grid spacing in texture pixels (Sillion 97 section 4.2)")
      ->capture_default_str()->check(CLI::Range(4, 256));
  cmd->add_option("--display-size", o->bake.impostor.display_width, "display width the threshold is given at")
      ->capture_default_str();
  cmd->add_option("--impostor-route", o->only_route,
                  "bake impostors only for the cells of a drive (auto:N with --seed), e.g. for benchmarks");
  cmd->add_option("--seed", o->seed, "seed of --impostor-route")->capture_default_str();
  cmd->add_option("--report", o->report_dir, "write an HTML bake report (map, impostor thumbnails) to this folder");
  cmd->callback([o, &run] {
    run = [o] {
      o->bake.draco = !o->no_draco;
      const std::string& m = o->impostor;
      o->bake.impostor.mode = m == "none"     ? bake::ImpostorMode::None
                              : m == "single" ? bake::ImpostorMode::Single
                              : m == "both"   ? bake::ImpostorMode::Both
                                              : bake::ImpostorMode::Layered;
      if (!o->only_route.empty()) {
        unsigned n = 0;
        if (std::sscanf(o->only_route.c_str(), "auto:%u", &n) != 1 || n == 0)
          throw core::Error(core::Status::InvalidArg, "--impostor-route must be auto:N");
        o->bake.select_cells = [n, seed = o->seed](const graph::StreetGraph& g) { return autoRoute(g, n, seed); };
      }
      if (!o->report_dir.empty())
        o->bake.on_impostors = [o](const graph::StreetGraph& g, const bake::ImpostorBakeResult& r) {
          writeBakeReport(o->report_dir, o->in, g, r);
        };
      const bake::BakeSummary s = bake::bakeCity(o->in, o->out, o->bake);
      std::printf(
          "baked %s -> %s in %.2f s\n"
          "  streets %zu, junctions %zu, graph vertices %zu, cells %zu, blocks %zu\n"
          "  buildings %zu (%zu at the default height %.1f m, %zu skipped, %zu unassembled polygons)\n"
          "  triangles %llu\n"
          "  impostors %zu meshes on %zu cells, %llu triangles, %llu bytes; %zu item-buffer samples in %.1f s, "
          "impostors in %.1f s\n"
          "  package %llu bytes, source %llu bytes, package/source = %.2f\n",
          o->in.c_str(), o->out.c_str(), s.seconds, s.streets, s.junctions, s.vertices, s.cells, s.blocks,
          s.buildings, s.defaulted_heights, o->bake.osm.default_height_m, s.skipped_buildings, s.bad_polygons,
          static_cast<unsigned long long>(s.triangles), s.impostors, s.impostor_cells,
          static_cast<unsigned long long>(s.impostor_triangles), static_cast<unsigned long long>(s.impostor_bytes),
          s.item_samples, s.pvs_seconds, s.impostor_seconds, static_cast<unsigned long long>(s.package_bytes),
          static_cast<unsigned long long>(s.source_bytes),
          s.source_bytes ? double(s.package_bytes) / double(s.source_bytes) : 0.0);
      return 0;
    };
  });
}

}  // namespace blvd::cli
