#include "bake/bake.h"

#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>

#include <sys/resource.h>

#include <glm/common.hpp>
#include <nlohmann/json.hpp>

#include "bake/block_mesh.h"
#include "bake/digest.h"
#include "bake/local_model.h"
#include "bake/progress.h"
#include "bake/pool_sizing.h"
#include "bake/street_map.h"
#include "bake/terrain.h"
#include "bake/tile.h"
#include "bake/triangulate.h"
#include "blvd/blvd.h"
#include "core/log.h"
#include "graph/block_table.h"
#include "graph/segment_grid.h"
#include "package/format.h"
#include "package/glb.h"
#include "package/writer.h"

namespace blvd::bake {

namespace {

// Each face's buildings: the face that holds the building's anchor point.
std::vector<std::vector<uint32_t>> placeBuildings(const OsmCity& city, StreetMap& map, BakeSummary& sum,
                                                  Progress& progress) {
  const graph::StreetGraph& g = map.graph();
  std::vector<std::vector<uint32_t>> face_buildings(g.faces.size());
  for (size_t i = 0; i < city.buildings.size(); ++i) {
    glm::dvec2 p;
    if (!buildingAnchor(city.buildings[i], p)) {
      ++sum.skipped_buildings;
      continue;
    }
    face_buildings[map.locateFace(p)].push_back(static_cast<uint32_t>(i));
    progress.update(double(i), double(city.buildings.size()));
  }
  return face_buildings;
}

// Terrain rules (bake/terrain.h): ground and streets draped where an edge's
// midpoint is more than 5 cm off the DEM's bilinear surface (DrapeTolerance),
// a building's base found on a grid of kBaseStepM inside its footprint (a
// third of SRTM3's 90 m spacing).
constexpr DrapeTolerance kDrape{};
constexpr double kBaseStepM = 30.0;

// A ground surface (block ground, half street) onto the terrain, if any. A
// street is raised by the room the ground's straight edges may need over a
// crease of the slope under it (half the shortest edge times the slope: a
// crease's worst change of slope is twice the slope, its error a quarter of
// the edge times that), at most kTerrainStreetLift.
void onGround(geo::MeshData& part, const TerrainHeight* terrain, bool street = false) {
  if (!terrain) return;
  subdivideForTerrain(part, *terrain, kDrape);
  drapeOnTerrain(part, *terrain);
  if (street) raiseBySlope(part, *terrain, 0.5 * kDrape.min_edge_m, kTerrainStreetLift);
}

// The city's east/north box: every street point and building.
void cityBox(const OsmCity& city, const graph::StreetGraph& g, glm::dvec2& lo, glm::dvec2& hi) {
  lo = glm::dvec2(std::numeric_limits<double>::infinity()), hi = glm::dvec2(-std::numeric_limits<double>::infinity());
  for (const glm::dvec2& p : g.points) lo = glm::min(lo, p), hi = glm::max(hi, p);
  for (const OsmBuilding& b : city.buildings)
    for (const Polygon2& poly : b.polygons)
      for (const glm::dvec2& p : poly.outer.pts) lo = glm::min(lo, p), hi = glm::max(hi, p);
}

// The DEM of --dem, read and checked to cover the city's box (as latitudes
// and longitudes).
std::unique_ptr<Dem> loadDem(const OsmCity& city, const graph::StreetGraph& g, const std::vector<std::string>& files,
                             BakeSummary& sum) {
  auto dem = std::make_unique<Dem>();
  for (const std::string& f : files) dem->addFile(f);
  glm::dvec2 lo, hi;
  cityBox(city, g, lo, hi);
  const geo::LocalFrame frame(city.origin_lat, city.origin_lon);
  double lat_lo = 90, lat_hi = -90, lon_lo = 180, lon_hi = -180;
  for (const glm::dvec2& c : {lo, hi, glm::dvec2(lo.x, hi.y), glm::dvec2(hi.x, lo.y)}) {
    double lat, lon, h;
    frame.reverse(geo::Enu{c.x, c.y, 0}, lat, lon, h);
    lat_lo = std::min(lat_lo, lat), lat_hi = std::max(lat_hi, lat), lon_lo = std::min(lon_lo, lon), lon_hi = std::max(lon_hi, lon);
  }
  dem->requireCovers(lat_lo, lon_lo, lat_hi, lon_hi);
  for (const DemTile& t : dem->tiles()) sum.dem_voids += t.voids;
  return dem;
}

// One block per face: ground, half streets and buildings, its LOD chain as a
// GLB blob in the package; the meshes are kept for the impostor captures.
// With a terrain, the ground and streets are draped and each building stands
// at the lowest ground under it.
void buildBlocks(const OsmCity& city, StreetMap& map, const std::vector<std::vector<uint32_t>>& face_buildings,
                 const BakeOptions& opt, const TerrainHeight* terrain, package::PackageWriter& writer,
                 std::vector<graph::BlockRecord>& blocks, std::vector<geo::MeshData>& block_meshes, BakeSummary& sum,
                 Progress& progress) {
  const graph::StreetGraph& g = map.graph();
  std::vector<std::vector<uint32_t>> face_halfedges(g.faces.size());
  for (uint32_t h = 0; h < g.halfedges.size(); ++h) face_halfedges[g.halfedges[h].face].push_back(h);
  blocks.assign(g.faces.size(), graph::BlockRecord{});
  block_meshes.assign(g.faces.size(), geo::MeshData{});
  package::GlbOptions glb_opt;
  glb_opt.codec = opt.block_codec;
  glb_opt.compression_level = opt.draco_level;
  for (uint32_t f = 0; f < g.faces.size(); ++f) {
    geo::MeshData& mesh = block_meshes[f];
    graph::BlockRecord& rec = blocks[f];
    if (g.faces[f].unbounded) rec.flags |= graph::kBlockUnbounded;
    std::string why;
    geo::MeshData part;
    if (!g.faces[f].unbounded &&
        appendBlockGround(g, f, [&](glm::dvec2 p) { return map.locateFace(p) == f; }, part, why)) {
      onGround(part, terrain);
      mesh.append(part);
    }
    for (uint32_t h : face_halfedges[f]) {
      part.clear();
      appendHalfStreet(g, h, part);
      onGround(part, terrain, true);
      mesh.append(part);
    }
    for (uint32_t b : face_buildings[f]) {
      part.clear();
      if (appendBuilding(city.buildings[b], part, why)) {
        if (terrain) raise(part, lowestUnder(city.buildings[b].polygons, *terrain, kBaseStepM));
        mesh.append(part);
        ++rec.building_count;
      } else {
        ++sum.skipped_buildings;
        BLVD_LOG_DEBUG("building %lld skipped: %s", static_cast<long long>(city.buildings[b].id), why.c_str());
      }
    }
    sum.buildings += rec.building_count;
    if (!mesh.empty()) {
      std::vector<uint8_t> glb = encodeBlock(mesh, opt.lod, glb_opt, rec, sum.lod);
      sum.triangles += rec.triangle_count;
      rec.blob = writer.addBlob(std::move(glb));
    }
    progress.update(double(f), double(g.faces.size()));
  }
  if (sum.skipped_buildings)
    BLVD_LOG_WARN("%zu buildings skipped (footprint unusable; see --verbose)", sum.skipped_buildings);
}

// Visibility and impostors of the cells (all, or `route`'s), into the package.
graph::CellTables impostorsOf(const graph::StreetGraph& g, const std::vector<geo::MeshData>& block_meshes,
                              const std::vector<uint32_t>& route, const BakeOptions& opt,
                              package::PackageWriter& writer, BakeSummary& sum, Progress& progress,
                              ShardManifest& shard) {
  if (opt.impostor.mode == ImpostorMode::None) return {};
  std::string current;
  ImpostorOptions iopt = opt.impostor;
  iopt.only_cells = route;
  iopt.shard_index = opt.shard.index;
  iopt.shard_count = opt.shard.count;
  const ImpostorBakeResult ir =
      bakeImpostors(g, block_meshes, iopt, writer, [&](const char* stage, double d, double t) {
        if (current != stage) progress.stage(current = stage);
        progress.update(d, t);
      });
  sum.impostors = ir.records.size();
  sum.item_samples = ir.samples;
  sum.pvs_seconds = ir.pvs_seconds;
  sum.impostor_seconds = ir.impostor_seconds;
  for (const auto& c : ir.tables.impostors) sum.impostor_cells += !c.layered.empty() || !c.single.empty();
  for (const auto& r : ir.records) {
    sum.impostor_triangles += r.triangles;
    sum.impostor_bytes += r.bytes;
  }
  if (opt.on_impostors) opt.on_impostors(g, ir, sum.lod);
  shard.streets = ir.shard_streets;
  shard.plan_costs = ir.shard_costs;
  shard.blocks_drawn = ir.shard_blocks_drawn;
  shard.plan_sha256 = planDigest(ir.shard_plan);
  for (const auto& p : ir.shard_plan) shard.plan_streets += p.size();
  return ir.tables;
}

// The header: origin, bounds of every block, counts and the pool sizes.
package::PackageHeader packageHeader(const OsmCity& city, const graph::StreetGraph& g,
                                     const std::vector<graph::BlockRecord>& blocks, const graph::CellTables& tables,
                                     const package::PackageWriter& writer, const BakeSummary& sum) {
  float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  bool any = false;
  for (const graph::BlockRecord& rec : blocks) {
    if (rec.lod_count == 0) continue;
    for (int k = 0; k < 3; ++k) {
      lo[k] = any ? std::min(lo[k], rec.bbox_min[k]) : rec.bbox_min[k];
      hi[k] = any ? std::max(hi[k], rec.bbox_max[k]) : rec.bbox_max[k];
    }
    any = true;
  }
  package::PackageHeader hdr;
  hdr.origin_lat = city.origin_lat;
  hdr.origin_lon = city.origin_lon;
  hdr.bounds_min[0] = lo[0];
  hdr.bounds_min[1] = -hi[2];  // glTF z is south
  hdr.bounds_max[0] = hi[0];
  hdr.bounds_max[1] = -lo[2];
  hdr.junction_count = static_cast<uint32_t>(g.junctionCount());
  hdr.cell_count = static_cast<uint32_t>(g.cellCount());
  hdr.block_count = static_cast<uint32_t>(g.faces.size());
  hdr.building_count = static_cast<uint32_t>(sum.buildings);
  hdr.triangle_count = sum.triangles;
  hdr.source_bytes = city.source_bytes;
  fillPoolSizing(g, blocks, tables, [&](uint32_t i) { return uint64_t{writer.blob(i).size()}; }, hdr);
  return hdr;
}

// The META section: how the package was baked, with the source's attribution.
std::string packageMeta(const std::string& osm_path, const OsmCity& city, const BakeOptions& opt,
                        const TileLayout& tiles, const std::vector<uint32_t>& route, const BakeSummary& sum) {
  const char* mode = opt.impostor.mode == ImpostorMode::None     ? "none"
                     : opt.impostor.mode == ImpostorMode::Single ? "single"
                     : opt.impostor.mode == ImpostorMode::Both   ? "both"
                                                                 : "layered";
  nlohmann::json meta = {
      {"generator", "blvd bake"},
      {"source", osm_path.substr(osm_path.find_last_of('/') + 1)},
      {"attribution", "© OpenStreetMap contributors (ODbL 1.0)"},
      {"default_height_m", opt.osm.default_height_m},
      {"level_height_m", opt.osm.level_height_m},
      {"draco", opt.block_codec == package::GlbCodec::Draco},
      {"block_codec", package::glbCodecName(opt.block_codec)},
      {"draco_level", opt.draco_level},
      {"blob_compression", opt.blob_compression},
      {"local_radius_m", opt.local_radius_m},
      {"junction_radius_m", opt.junction_radius_m},
      {"tile",
       {{"nx", opt.tile.nx}, {"ny", opt.tile.ny}, {"gap_m", opt.tile.gap_m},
        {"step_m", {tiles.step.x, tiles.step.y}}, {"cells_per_tile", tiles.cells},
        {"blocks_per_tile", tiles.blocks}, {"vertices_per_tile", tiles.vertices}, {"blobs_per_tile", tiles.blobs}}},
      {"impostor_route", route},
      {"lod",
       {{"mode", opt.lod.enabled ? "chain" : "none"},
        {"ratios", opt.lod.ratios},
        {"blocks_per_level", sum.lod.blocks},
        {"triangles_per_level", sum.lod.triangles},
        {"vertices_per_level", sum.lod.vertices},
        {"sloppy_levels", sum.lod.sloppy_levels},
        {"unlocked_levels", sum.lod.unlocked_levels},
        {"max_error_m", sum.lod.max_error_m}}},
      {"impostors",
       {{"mode", mode},
        {"threshold_px", opt.impostor.threshold_px},
        {"texture_max", opt.impostor.texture_max},
        {"grid_px", opt.impostor.grid_px},
        {"skirt_px", opt.impostor.skirt_px},
        {"texture_codec", opt.impostor.texture_codec == TextureCodec::Webp ? "webp" : "jpeg"},
        {"texture_quality", opt.impostor.texture_quality},
        {"mesh_codec", package::glbCodecName(opt.impostor.mesh_codec)},
        {"mesh_bits", {opt.impostor.mesh_position_bits, opt.impostor.mesh_texcoord_bits}},
        {"display", {opt.impostor.display_width, opt.impostor.display_height, opt.impostor.display_fov_y_deg}}}},
      {"counts",
       {{"streets", sum.streets}, {"buildings", sum.buildings}, {"height_tagged", city.height_tagged},
        {"level_tagged", city.level_tagged}, {"defaulted", city.defaulted}, {"skipped", sum.skipped_buildings}}},
  };
  if (!opt.dem.empty()) {  // only then: a flat bake's META stays as it was
    std::vector<std::string> names;
    for (const std::string& f : opt.dem) names.push_back(f.substr(f.find_last_of('/') + 1));
    meta["terrain"] = {{"dem", names},
                       {"dem_voids_filled", sum.dem_voids},
                       {"ground_m", {sum.ground_min_m, sum.ground_max_m}},
                       {"drape", {{"max_edge_m", kDrape.max_edge_m}, {"min_edge_m", kDrape.min_edge_m}, {"height_m", kDrape.height_m}}},
                       {"base_step_m", kBaseStepM},
                       {"tiles",
                        {{"grid", opt.terrain_tiles.grid},
                         {"levels", sum.terrain_levels},
                         {"count", sum.terrain_tiles},
                         {"spacing_m", opt.terrain_tiles.spacing_m},
                         {"margin_m", opt.terrain_tiles.margin_m},
                         {"root_error_m", sum.terrain_error_m},
                         {"uncovered_points", sum.terrain_uncovered}}}};
  }
  return meta.dump(1);
}

// CPU seconds of this process so far, every thread's, user and system.
double cpuSeconds() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  auto sec = [](const timeval& t) { return double(t.tv_sec) + 1e-6 * double(t.tv_usec); };
  return sec(ru.ru_utime) + sec(ru.ru_stime);
}

// The manifest of a shard file: who it is, what it was baked from.
ShardManifest& identifyShard(ShardManifest& m, const std::string& osm_path, const OsmCity& city,
                             const BakeOptions& opt, const std::vector<uint32_t>& route, uint32_t block_blobs) {
  m.index = opt.shard.index;
  m.count = opt.shard.count;
  m.input_name = osm_path.substr(osm_path.find_last_of('/') + 1);
  m.input_bytes = city.source_bytes;
  m.input_sha256 = sha256FileHex(osm_path);
  m.options_sha256 = sha256Hex(bakeIdentityJson(opt, route));
  m.generator = "blvd bake " + std::to_string(BLVD_VERSION_MAJOR) + "." + std::to_string(BLVD_VERSION_MINOR) + "." +
                std::to_string(BLVD_VERSION_PATCH);
  m.block_blobs = block_blobs;
  return m;
}

// TERR (docs/package-format.md): the terrain's quadtree tiles over the
// city's box and a margin, their heights as blobs after the city's; none
// when the ground there is level within kFlatTerrainM (a flat DEM then bakes
// the flat city's package but for the draped ground and ELEV).
constexpr float kFlatTerrainM = 0.5f;

std::vector<uint8_t> terrainTiles(const Dem& dem, const OsmCity& city, const graph::StreetGraph& g,
                                  TerrainTileOptions opt, package::PackageWriter& writer, BakeSummary& sum) {
  const geo::LocalFrame frame(city.origin_lat, city.origin_lon);
  glm::dvec2 lo, hi;
  cityBox(city, g, lo, hi);
  opt.fill_m = -frame.h0();  // the sea's level
  TerrainTileSet set = buildTerrainTiles(demHeights(dem, frame), lo, hi, opt);
  float low = set.records[0].min_m, high = set.records[0].max_m;
  for (const graph::TerrainRecord& r : set.records) low = std::min(low, r.min_m), high = std::max(high, r.max_m);
  if (high - low <= kFlatTerrainM) return {};  // level ground: the runtime's background draws it already
  for (graph::TerrainRecord& r : set.records) r.blob = writer.addBlob(std::move(set.blobs[r.blob]));
  sum.terrain_tiles = set.records.size();
  sum.terrain_levels = set.layout.levels;
  sum.terrain_uncovered = set.uncovered;
  sum.terrain_error_m = set.records.empty() ? 0.0 : set.records[0].error_m;
  return graph::serializeTerrain(set.layout, set.records);
}

// ELEV (docs/package-format.md): the ground's height at every graph point.
std::vector<uint8_t> elevationSection(const graph::StreetGraph& g, const TerrainHeight& terrain, BakeSummary& sum) {
  std::vector<uint8_t> out(8 + 4 * g.points.size());
  const uint32_t head[2] = {1, static_cast<uint32_t>(g.points.size())};
  std::memcpy(out.data(), head, 8);
  sum.ground_min_m = std::numeric_limits<double>::infinity();
  sum.ground_max_m = -std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < g.points.size(); ++i) {
    const double h = terrain(g.points[i]);
    const auto f = static_cast<float>(h);
    std::memcpy(out.data() + 8 + 4 * i, &f, 4);
    sum.ground_min_m = std::min(sum.ground_min_m, h), sum.ground_max_m = std::max(sum.ground_max_m, h);
  }
  if (g.points.empty()) sum.ground_min_m = sum.ground_max_m = 0;
  return out;
}

// A tiled bake repeats the city: its counts grow with the copies.
void scaleForTiles(const TileLayout& tiles, BakeSummary& sum) {
  const uint64_t n = tiles.copies;
  sum.buildings *= n;
  sum.triangles *= n;
  for (uint32_t k = 0; k < graph::kMaxBlockLods; ++k)
    sum.lod.blocks[k] *= n, sum.lod.triangles[k] *= n, sum.lod.vertices[k] *= n;
}

}  // namespace

void addPackageSections(package::PackageWriter& w, PackageSections s, const graph::CellTables& tables) {
  w.addSection(package::kSectionGraph, std::move(s.graph));
  w.addSection(package::kSectionCells, std::move(s.cells));
  w.addSection(package::kSectionSpatialIndex, std::move(s.spatial_index));
  w.addSection(package::kSectionBlocks, std::move(s.blocks));
  if (!tables.visibility.empty()) {
    std::vector<uint64_t> visibility_at, impostors_at;
    w.addSection(package::kSectionVisibility, graph::serializeVisibility(tables, &visibility_at));
    w.addSection(package::kSectionImpostors, graph::serializeImpostors(tables, &impostors_at));
    w.addSection(package::kSectionCellTableIndex, graph::serializeCellTableIndex(visibility_at, impostors_at));
  }
  w.addSection(package::kSectionMeta, std::move(s.meta));
}

std::string metaWithBlobCount(const std::vector<uint8_t>& meta, uint32_t blobs) {
  nlohmann::json j = nlohmann::json::parse(meta.begin(), meta.end());
  j["tile"]["blobs_per_tile"] = blobs;
  return j.dump(1);
}

std::string bakeIdentityJson(const BakeOptions& opt, const std::vector<uint32_t>& route) {
  const ImpostorOptions& i = opt.impostor;
  const nlohmann::json j = {
      {"osm", {opt.osm.default_height_m, opt.osm.level_height_m}},
      {"blocks", {package::glbCodecName(opt.block_codec), opt.draco_level, opt.local_radius_m, opt.junction_radius_m}},
      {"blob_compression", opt.blob_compression},
      {"lod", {opt.lod.enabled, opt.lod.ratios}},
      {"tile", {opt.tile.nx, opt.tile.ny, opt.tile.gap_m}},
      {"impostor",
       {int(i.mode), i.texture_max, i.threshold_px, i.max_layers, i.display_width, i.display_height,
        i.display_fov_y_deg, i.grid_px, i.skirt_px, i.positions_per_cell, i.item_resolution, i.vantage_at,
        i.max_span_deg, i.view_margin_deg, i.cell_texels, i.run_length_m, i.run_turn_deg, i.run_climb_m, i.max_runs,
        i.landmark_height_m, i.landmark_scale, int(i.texture_codec), i.texture_quality, i.edge_on_cos,
        package::glbCodecName(i.mesh_codec), i.mesh_position_bits, i.mesh_texcoord_bits}},
      {"route", route},
  };
  if (opt.dem.empty()) return j.dump();  // a flat bake's identity as it was
  nlohmann::json with_dem = j;
  for (const std::string& f : opt.dem) with_dem["dem"].push_back(sha256FileHex(f));
  return with_dem.dump();
}

BakeSummary bakeCity(const std::string& osm_path, const std::string& out_path, const BakeOptions& opt) {
  const auto t0 = std::chrono::steady_clock::now();
  checkLodOptions(opt.lod);
  if (opt.shard.count > 0 && (opt.tile.nx * opt.tile.ny > 1 || opt.on_impostors))
    throw core::Error(core::Status::InvalidArg, "a shard of a bake cannot be tiled or reported: merge the shards first");
  if (!opt.dem.empty() && opt.tile.nx * opt.tile.ny > 1)
    throw core::Error(core::Status::InvalidArg,
                      "--dem cannot be combined with --tile: the copies would stand on ground the DEM does not hold");
  if (opt.shard.count > 0 && opt.shard.index >= opt.shard.count)
    throw core::Error(core::Status::InvalidArg, "shard " + std::to_string(opt.shard.index) + " of " +
                                                    std::to_string(opt.shard.count) + ": the index must be below the count");
  BakeSummary sum;
  Progress progress(opt.quiet);

  progress.stage("reading " + osm_path.substr(osm_path.find_last_of('/') + 1));
  OsmCity city = readOsm(osm_path, opt.osm, [&](uint64_t d, uint64_t t) { progress.update(double(d), double(t)); });
  sum.streets = city.streets.size();
  sum.source_bytes = city.source_bytes;
  sum.bad_polygons = city.bad_polygons;
  sum.defaulted_heights = city.defaulted;

  progress.stage("street map (arrangement)");
  StreetMap map(city.streets);
  graph::StreetGraph& g = map.graph();
  std::unique_ptr<Dem> dem;
  TerrainHeight terrain;
  if (!opt.dem.empty()) {
    progress.stage("terrain (DEM)");
    dem = loadDem(city, g, opt.dem, sum);
    terrain = demTerrain(*dem, geo::LocalFrame(city.origin_lat, city.origin_lon));
  }
  progress.stage("placing buildings");
  const std::vector<std::vector<uint32_t>> face_buildings = placeBuildings(city, map, sum, progress);
  widenLocalModels(g, city.buildings, face_buildings, opt.local_radius_m, opt.junction_radius_m);
  progress.stage("block geometry + LOD chain + GLB");
  package::PackageWriter writer;
  writer.setBlobCompression(opt.blob_compression);
  std::vector<graph::BlockRecord> blocks;
  std::vector<geo::MeshData> block_meshes;
  buildBlocks(city, map, face_buildings, opt, terrain ? &terrain : nullptr, writer, blocks, block_meshes, sum, progress);
  // The terrain's blobs next, before any impostor's: every shard writes them
  // alike, so a merge copies them with the blocks'.
  std::vector<uint8_t> terrain_section;
  if (dem) terrain_section = terrainTiles(*dem, city, g, opt.terrain_tiles, writer, sum);

  // Chosen on the city before any tiling, so the same cells in a 1x and a tiled package.
  const std::vector<uint32_t> route = opt.select_cells ? opt.select_cells(g) : std::vector<uint32_t>{};
  const uint32_t block_blobs = writer.blobCount();
  ShardManifest shard;
  BakeOptions with_ground = opt;
  with_ground.impostor.ground = terrain;
  graph::CellTables tables = impostorsOf(g, block_meshes, route, with_ground, writer, sum, progress, shard);

  const bool tiled = opt.tile.nx * opt.tile.ny > 1;
  if (tiled) progress.stage("tiling " + std::to_string(opt.tile.nx) + "x" + std::to_string(opt.tile.ny));
  TileLayout tiles = tileCity(g, blocks, tables, writer, opt.tile);  // 1x1: no change
  if (opt.shard.count > 0) tiles.blobs = 0;  // the package's blob count: the merge sets it (metaWithBlobCount)
  if (tiled) scaleForTiles(tiles, sum);

  progress.stage("writing package");
  const std::vector<std::string> bad = graph::checkInvariants(g);
  if (!bad.empty()) throw core::Error(core::Status::Internal, "street graph invariant broken: " + bad.front());
  writer.setHeader(packageHeader(city, g, blocks, tables, writer, sum));
  graph::SegmentGrid grid;
  grid.build(g);
  const std::vector<uint8_t> elevation = terrain ? elevationSection(g, terrain, sum) : std::vector<uint8_t>{};
  const std::string meta = packageMeta(osm_path, city, opt, tiles, route, sum);
  addPackageSections(writer,
                     {graph::serializeGraph(g), graph::serializeCells(g), graph::serializeSegmentGrid(grid),
                      graph::serializeBlocks(blocks), std::vector<uint8_t>(meta.begin(), meta.end())},
                     tables);
  if (terrain) writer.addSection(package::kSectionElevation, elevation);
  if (!terrain_section.empty()) writer.addSection(package::kSectionTerrain, terrain_section);
  if (opt.shard.count > 0) {
    identifyShard(shard, osm_path, city, opt, route, block_blobs);
    shard.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    shard.cpu_seconds = cpuSeconds();
    const std::string m = manifestJson(shard);
    writer.addSection(package::kSectionShard, std::vector<uint8_t>(m.begin(), m.end()));
    sum.shard_streets = shard.streets;
  }
  writer.write(out_path);
  sum.package_bytes = writer.fileBytes();
  progress.finish();

  sum.junctions = g.junctionCount();
  sum.vertices = g.vertices.size();
  sum.cells = g.cellCount();
  for (uint32_t h = 0; h < g.halfedges.size(); ++h)
    if (g.halfedges[h].twin > h || g.halfedges[h].twin == graph::kNone) sum.street_km += g.halfedges[h].length / 1000.0;
  sum.blocks = g.faces.size();
  sum.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return sum;
}

}  // namespace blvd::bake
