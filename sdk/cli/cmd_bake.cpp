#include <algorithm>
#include <cstdio>
#include <cstdlib>

#include "bake/bake.h"
#include "bake/rig_pool.h"
#include "cli/bake_report.h"
#include "cli/commands.h"
#include "cli/route.h"
#include "core/status.h"

namespace blvd::cli {
namespace {
// "0.5,0.25,0.1" -> {0.5, 0.25, 0.1}; the bake checks the values.
std::vector<double> parseRatios(const std::string& text) {
  std::vector<double> r;
  size_t pos = 0;
  while (pos <= text.size()) {
    const size_t comma = std::min(text.find(',', pos), text.size());
    const std::string item = text.substr(pos, comma - pos);
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || end != item.c_str() + item.size())
      throw core::Error(core::Status::InvalidArg, "--lod-ratios: '" + item + "' is not a number (expected e.g. 0.5,0.25,0.1)");
    r.push_back(v);
    pos = comma + 1;
  }
  return r;
}

// The bake's summary on stdout; with impostors, what a cell and a layer cost.
void printSummary(const bake::BakeSummary& s, const std::string& in, const std::string& out, double default_height_m) {
  std::printf(
      "baked %s -> %s in %.2f s\n"
      "  streets %zu, junctions %zu, graph vertices %zu, cells %zu, blocks %zu\n"
      "  buildings %zu (%zu at the default height %.1f m, %zu skipped, %zu unassembled polygons)\n"
      "  triangles %llu; LOD levels 0-3: %llu/%llu/%llu/%llu blocks, %llu/%llu/%llu/%llu triangles, "
      "%llu sloppy, max error %.2f m, simplification %.1f s\n"
      "  impostors %zu meshes on %zu cells, %llu triangles, %llu bytes; %zu item-buffer samples in %.1f s, "
      "impostors in %.1f s\n"
      "  package %llu bytes, source %llu bytes, package/source = %.2f\n",
      in.c_str(), out.c_str(), s.seconds, s.streets, s.junctions, s.vertices, s.cells, s.blocks,
      s.buildings, s.defaulted_heights, default_height_m, s.skipped_buildings, s.bad_polygons,
      static_cast<unsigned long long>(s.triangles), static_cast<unsigned long long>(s.lod.blocks[0]),
      static_cast<unsigned long long>(s.lod.blocks[1]), static_cast<unsigned long long>(s.lod.blocks[2]),
      static_cast<unsigned long long>(s.lod.blocks[3]), static_cast<unsigned long long>(s.lod.triangles[0]),
      static_cast<unsigned long long>(s.lod.triangles[1]), static_cast<unsigned long long>(s.lod.triangles[2]),
      static_cast<unsigned long long>(s.lod.triangles[3]), static_cast<unsigned long long>(s.lod.sloppy_levels),
      s.lod.max_error_m, s.lod.seconds, s.impostors, s.impostor_cells,
      static_cast<unsigned long long>(s.impostor_triangles), static_cast<unsigned long long>(s.impostor_bytes),
      s.item_samples, s.pvs_seconds, s.impostor_seconds, static_cast<unsigned long long>(s.package_bytes),
      static_cast<unsigned long long>(s.source_bytes),
      s.source_bytes ? double(s.package_bytes) / double(s.source_bytes) : 0.0);
  if (s.ground_max_m > s.ground_min_m)
    std::printf("  terrain: the streets from %.1f to %.1f m (%llu DEM voids filled)\n", s.ground_min_m, s.ground_max_m,
                static_cast<unsigned long long>(s.dem_voids));
  if (s.terrain_tiles)
    std::printf("  terrain tiles: %llu in %u levels, root error %.1f m (%llu grid points outside the DEM, at sea level)\n",
                static_cast<unsigned long long>(s.terrain_tiles), s.terrain_levels, s.terrain_error_m,
                static_cast<unsigned long long>(s.terrain_uncovered));
  if (s.street_km > 0 && s.cells > 0)
    std::printf("  package per km of street %.0f bytes (%.1f km), per cell %.0f bytes\n",
                double(s.package_bytes) / s.street_km, s.street_km, double(s.package_bytes) / double(s.cells));
  if (s.impostor_cells > 0 && s.impostors > 0 && s.item_samples > 0)
    std::printf("  per impostor cell %.2f s (item buffers %.1f ms a sample), %.1f ms an impostor mesh\n",
                (s.pvs_seconds + s.impostor_seconds) / double(s.impostor_cells),
                1000.0 * s.pvs_seconds / double(s.item_samples), 1000.0 * s.impostor_seconds / double(s.impostors));
}

}  // namespace

void addBake(CLI::App& app, Runner& run) {
  auto* cmd = app.add_subcommand("bake", "bake an OpenStreetMap extract into a .blvd package");
  struct Opts {
    std::string in, out, report_dir;
    bake::BakeOptions bake;
    bool no_draco = false;
    std::string block_codec = "meshopt", impostor_codec = "draco";
    std::string impostor = "layered", texture_codec = "webp", only_route, lod = "chain", lod_ratios = "0.5,0.25,0.1", tile = "1x1";
    uint64_t seed = 1;
    std::string shard;
    uint32_t shards = 0;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("input", o->in, "OpenStreetMap extract: .osm.pbf, .osm, .osm.gz or .osm.bz2")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", o->out, "package to write (.blvd)")->required();
  cmd->add_option("--default-height", o->bake.osm.default_height_m,
                  "height of buildings without height or building:levels tags, metres")
      ->capture_default_str()->check(CLI::Range(1.0, 500.0));
  cmd->add_option("--level-height", o->bake.osm.level_height_m, "metres per building:levels level")
      ->capture_default_str()->check(CLI::Range(1.0, 10.0));
  cmd->add_flag("--quiet", o->bake.quiet, "plain log lines, no progress bar");
  cmd->add_option("--block-codec", o->block_codec,
                  "how block levels are stored: meshopt (EXT_meshopt_compression, fast decode), draco (smallest) "
                  "or plain")
      ->capture_default_str()
      ->check(CLI::IsMember({"meshopt", "draco", "plain"}));
  cmd->add_flag("--no-draco", o->no_draco, "same as --block-codec plain");
  cmd->add_option("--draco-level", o->bake.draco_level,
                  "Draco compression of the block levels (--block-codec draco): 0 (fastest decode, biggest) .. 10 (smallest)")
      ->capture_default_str()
      ->check(CLI::Range(0, 10));
  cmd->add_option("--blob-compression", o->bake.blob_compression,
                  "zstd level the package stores every blob at: 0 (as is) .. 22 (smallest, slowest bake); decoding "
                  "costs the same at any level")
      ->capture_default_str()
      ->check(CLI::Range(0, 22));
  cmd->add_option("--lod", o->lod, "per-block levels of detail: chain (meshoptimizer, see --lod-ratios) or none")
      ->capture_default_str()->check(CLI::IsMember({"chain", "none"}));
  cmd->add_option("--lod-ratios", o->lod_ratios,
                  "triangle shares of the full mesh the simplified levels aim at, decreasing, at most 3")
      ->capture_default_str();
  cmd->add_option("--tile", o->tile,
                  "NxM disconnected copies of the city, N east by M north (benchmark packages: 2x2 is 4x the city)")
      ->capture_default_str();
  cmd->add_option("--tile-gap", o->bake.tile.gap_m, "metres between the copies of --tile")
      ->capture_default_str()->check(CLI::Range(0.0, 100000.0));
  cmd->add_option("--local-radius", o->bake.local_radius_m,
                  "a block with a building this close to a street is in its cell's local model, metres; 0: the "
                  "blocks touching the street and its junctions only (docs/decisions/0015)")
      ->capture_default_str()->check(CLI::Range(0.0, 200.0));
  cmd->add_option("--junction-radius", o->bake.junction_radius_m,
                  "a block bordering a street this close to a cell's end points is in its local model, metres; 0: "
                  "none (a junction drawn as several vertices, docs/decisions/0025)")
      ->capture_default_str()->check(CLI::Range(0.0, 50.0));
  cmd->add_option("--impostor", o->impostor,
                  "impostors per cell: layered (Decoret 99 MMI), single (Sillion 97), both, or none")
      ->capture_default_str()->check(CLI::IsMember({"layered", "single", "both", "none"}));
  cmd->add_option("--texture", o->bake.impostor.texture_max, "largest impostor texture side, pixels")
      ->capture_default_str()->check(CLI::Range(32, 4096));
  cmd->add_option("--texture-codec", o->texture_codec, "impostor textures: webp (EXT_texture_webp), or jpeg")
      ->capture_default_str()->check(CLI::IsMember({"jpeg", "webp"}));
  cmd->add_option("--impostor-codec", o->impostor_codec,
                  "how impostor depth meshes are stored: draco (smallest), meshopt (fast decode) or plain")
      ->capture_default_str()
      ->check(CLI::IsMember({"meshopt", "draco", "plain"}));
  cmd->add_option("--texture-quality,--jpeg-quality", o->bake.impostor.texture_quality, "impostor texture quality")
      ->capture_default_str()->check(CLI::Range(10, 100));
  cmd->add_option("--cell-texels", o->bake.impostor.cell_texels,
                  "texel budget of one cell's impostor captures together (docs/decisions/0010)")
      ->capture_default_str()->check(CLI::Range(4096, 1 << 26));
  cmd->add_option("--run-length", o->bake.impostor.run_length_m,
                  "a cell longer than this gets several impostor runs (vantage points), metres")
      ->capture_default_str()->check(CLI::Range(10.0, 100000.0));
  cmd->add_option("--run-climb", o->bake.impostor.run_climb_m,
                  "with --dem, a cell whose ground rises or falls more than this gets several runs, metres (0: off)")
      ->capture_default_str()->check(CLI::Range(0.0, 10000.0));
  cmd->add_option("--vantage", o->bake.impostor.vantage_at,
                  "where along its run a run's impostors are captured: 0 its start, 0.5 its middle, 1 its end "
                  "(docs/decisions/0025)")
      ->capture_default_str()->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--max-runs", o->bake.impostor.max_runs, "most impostor runs a cell gets")
      ->capture_default_str()->check(CLI::Range(1, 16));
  cmd->add_option("--max-span", o->bake.impostor.max_span_deg,
                  "widest azimuth one impostor capture holds, degrees (docs/decisions/0010)")
      ->capture_default_str()->check(CLI::Range(10.0, 120.0));
  cmd->add_option("--jobs", o->bake.impostor.jobs,
                  "capture workers for item buffers and impostors, each with its own GL context (0: one per CPU); "
                  "the package is the same with any number")
      ->capture_default_str()->check(CLI::Range(0, 64));
  cmd->add_option("--skirt", o->bake.impostor.skirt_px,
                  "pixels of skirt hung under far geometry's lower edge in each capture (0: none)")
      ->capture_default_str()->check(CLI::Range(0, 8));
  cmd->add_option("--edge-on", o->bake.impostor.edge_on_cos,
                  "drop impostor triangles the capture saw this edge-on (|cos| from the vantage point) that either "
                  "end of the run sees at least twice as squarely; 0: keep all (docs/decisions/0015)")
      ->capture_default_str()->check(CLI::Range(0.0, 1.0));
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
  cmd->add_option("--dem", o->bake.dem,
                  "SRTM elevation tiles (.hgt or .hgt.zip, named by their south-west corner, e.g. N43E007.hgt.zip) "
                  "covering the city: the blocks stand on the terrain and the streets follow it")
      ->check(CLI::ExistingFile);
  cmd->add_option("--report", o->report_dir, "write an HTML bake report (map, impostor thumbnails) to this folder");
  cmd->add_option("--shard", o->shard,
                  "bake one shard into a shard file for `blvd pack merge`: I/N, I with --shards N, or env "
                  "(SLURM_ARRAY_TASK_ID or JOB_COMPLETION_INDEX; docs/cluster-bake.md)");
  cmd->add_option("--shards", o->shards, "number of shards (with --shard I or env)")->check(CLI::Range(1u, 1u << 20));
  cmd->callback([o, &run] {
    run = [o] {
      package::parseGlbCodec(o->no_draco ? "plain" : o->block_codec, o->bake.block_codec);
      package::parseGlbCodec(o->impostor_codec, o->bake.impostor.mesh_codec);
      o->bake.lod.enabled = o->lod == "chain";
      o->bake.lod.ratios = parseRatios(o->lod_ratios);
      unsigned nx = 0, ny = 0;
      char tail = 0;
      if (std::sscanf(o->tile.c_str(), "%ux%u%c", &nx, &ny, &tail) != 2 || nx == 0 || ny == 0 || nx * ny > 64)
        throw core::Error(core::Status::InvalidArg, "--tile must be NxM with 1 <= N*M <= 64, e.g. 2x2");
      o->bake.tile.nx = nx;
      o->bake.tile.ny = ny;
      const std::string& m = o->impostor;
      o->bake.impostor.mode = m == "none"     ? bake::ImpostorMode::None
                              : m == "single" ? bake::ImpostorMode::Single
                              : m == "both"   ? bake::ImpostorMode::Both
                                              : bake::ImpostorMode::Layered;
      o->bake.impostor.texture_codec = o->texture_codec == "webp" ? bake::TextureCodec::Webp : bake::TextureCodec::Jpeg;
      if (!o->only_route.empty()) {
        unsigned n = 0;
        if (std::sscanf(o->only_route.c_str(), "auto:%u", &n) != 1 || n == 0)
          throw core::Error(core::Status::InvalidArg, "--impostor-route must be auto:N");
        o->bake.select_cells = [n, seed = o->seed](const graph::StreetGraph& g) { return graph::seededRoute(g, {n, seed}); };
      }
      if (!o->report_dir.empty())
        o->bake.on_impostors = [o](const graph::StreetGraph& g, const bake::ImpostorBakeResult& r,
                                   const bake::LodStats& lod) {
          writeBakeReport(o->report_dir, o->in, g, r, lod);
        };
      // With a worker per core, llvmpipe's own rasteriser threads only
      // contend with them: each worker rasterises on its own thread
      // (docs/decisions/0016). A value the user set is kept.
      if (bake::RigPool::resolveWorkers(o->bake.impostor.jobs) > 1) ::setenv("LP_NUM_THREADS", "0", 0);
      if (!o->shard.empty()) {
        if (!o->report_dir.empty()) throw core::Error(core::Status::InvalidArg, "--report: not with --shard (a shard holds part of the cells)");
        o->bake.shard = bake::parseShardSpec(o->shard, o->shards, [](const char* k) -> const char* { return std::getenv(k); });
      } else if (o->shards) {
        throw core::Error(core::Status::InvalidArg, "--shards: give the shard with --shard I or --shard env");
      }
      const bake::BakeSummary sum = bake::bakeCity(o->in, o->out, o->bake);
      printSummary(sum, o->in, o->out, o->bake.osm.default_height_m);
      if (o->bake.shard.count)
        std::printf("  shard %u of %u: %zu streets; merge all %u with `blvd pack merge`\n", o->bake.shard.index,
                    o->bake.shard.count, sum.shard_streets.size(), o->bake.shard.count);
      return 0;
    };
  });
}

}  // namespace blvd::cli
