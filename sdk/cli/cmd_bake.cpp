#include <cstdio>

#include "bake/bake.h"
#include "cli/commands.h"

namespace blvd::cli {

void addBake(CLI::App& app, Runner& run) {
  auto* cmd = app.add_subcommand("bake", "bake an OpenStreetMap .osm.pbf into a .blvd package");
  struct Opts {
    std::string in, out;
    bake::BakeOptions bake;
    bool no_draco = false;
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
  cmd->callback([o, &run] {
    run = [o] {
      o->bake.draco = !o->no_draco;
      const bake::BakeSummary s = bake::bakeCity(o->in, o->out, o->bake);
      std::printf(
          "baked %s -> %s in %.2f s\n"
          "  streets %zu, junctions %zu, graph vertices %zu, cells %zu, blocks %zu\n"
          "  buildings %zu (%zu at the default height %.1f m, %zu skipped, %zu unassembled polygons)\n"
          "  triangles %llu\n"
          "  package %llu bytes, source %llu bytes, package/source = %.2f\n",
          o->in.c_str(), o->out.c_str(), s.seconds, s.streets, s.junctions, s.vertices, s.cells, s.blocks,
          s.buildings, s.defaulted_heights, o->bake.osm.default_height_m, s.skipped_buildings, s.bad_polygons,
          static_cast<unsigned long long>(s.triangles), static_cast<unsigned long long>(s.package_bytes),
          static_cast<unsigned long long>(s.source_bytes),
          s.source_bytes ? double(s.package_bytes) / double(s.source_bytes) : 0.0);
      return 0;
    };
  });
}

}  // namespace blvd::cli
