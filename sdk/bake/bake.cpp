#include "bake/bake.h"

#include <chrono>
#include <cmath>
#include <limits>

#include <nlohmann/json.hpp>

#include "bake/block_mesh.h"
#include "bake/progress.h"
#include "bake/street_map.h"
#include "bake/triangulate.h"
#include "core/log.h"
#include "graph/block_table.h"
#include "package/format.h"
#include "package/glb.h"
#include "package/writer.h"

namespace blvd::bake {

BakeSummary bakeCity(const std::string& osm_path, const std::string& out_path, const BakeOptions& opt) {
  const auto t0 = std::chrono::steady_clock::now();
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

  progress.stage("placing buildings");
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

  progress.stage("block geometry + GLB");
  std::vector<std::vector<uint32_t>> face_halfedges(g.faces.size());
  for (uint32_t h = 0; h < g.halfedges.size(); ++h) face_halfedges[g.halfedges[h].face].push_back(h);
  package::PackageWriter writer;
  std::vector<graph::BlockRecord> blocks(g.faces.size());
  uint32_t max_blob = 0;
  float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
  std::vector<geo::MeshData> block_meshes(g.faces.size());  // kept for the impostor captures
  package::GlbOptions glb_opt;
  glb_opt.draco = opt.draco;
  for (uint32_t f = 0; f < g.faces.size(); ++f) {
    geo::MeshData& mesh = block_meshes[f];
    graph::BlockRecord& rec = blocks[f];
    if (g.faces[f].unbounded) rec.flags |= graph::kBlockUnbounded;
    std::string why;
    if (!g.faces[f].unbounded)
      appendBlockGround(g, f, [&](glm::dvec2 p) { return map.locateFace(p) == f; }, mesh, why);
    for (uint32_t h : face_halfedges[f]) appendHalfStreet(g, h, mesh);
    for (uint32_t b : face_buildings[f]) {
      if (appendBuilding(city.buildings[b], mesh, why)) {
        ++rec.building_count;
      } else {
        ++sum.skipped_buildings;
        BLVD_LOG_DEBUG("building %lld skipped: %s", static_cast<long long>(city.buildings[b].id), why.c_str());
      }
    }
    sum.buildings += rec.building_count;
    rec.triangle_count = static_cast<uint32_t>(mesh.triangleCount());
    sum.triangles += rec.triangle_count;
    if (!mesh.empty()) {
      for (int k = 0; k < 3; ++k) {
        rec.bbox_min[k] = std::numeric_limits<float>::max();
        rec.bbox_max[k] = -std::numeric_limits<float>::max();
      }
      for (size_t v = 0; v < mesh.positions.size(); v += 3)
        for (int k = 0; k < 3; ++k) {
          rec.bbox_min[k] = std::min(rec.bbox_min[k], mesh.positions[v + k]);
          rec.bbox_max[k] = std::max(rec.bbox_max[k], mesh.positions[v + k]);
        }
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], rec.bbox_min[k]), hi[k] = std::max(hi[k], rec.bbox_max[k]);
      std::vector<uint8_t> glb = package::encodeGlb(mesh, glb_opt);
      max_blob = std::max<uint32_t>(max_blob, static_cast<uint32_t>(glb.size()));
      rec.blob = writer.addBlob(std::move(glb));
    }
    progress.update(double(f), double(g.faces.size()));
  }
  if (sum.skipped_buildings)
    BLVD_LOG_WARN("%zu buildings skipped (footprint unusable; see --verbose)", sum.skipped_buildings);

  graph::CellTables tables;
  if (opt.impostor.mode != ImpostorMode::None) {
    std::string current;
    ImpostorOptions iopt = opt.impostor;
    if (opt.select_cells) iopt.only_cells = opt.select_cells(g);
    const ImpostorBakeResult ir =
        bakeImpostors(g, block_meshes, iopt, writer, [&](const char* stage, double d, double t) {
          if (current != stage) progress.stage(current = stage);
          progress.update(d, t);
        });
    tables = ir.tables;
    sum.impostors = ir.records.size();
    sum.item_samples = ir.samples;
    sum.pvs_seconds = ir.pvs_seconds;
    sum.impostor_seconds = ir.impostor_seconds;
    for (const auto& c : tables.impostors) sum.impostor_cells += !c.layered.empty() || !c.single.empty();
    for (const auto& r : ir.records) {
      sum.impostor_triangles += r.triangles;
      sum.impostor_bytes += r.bytes;
    }
    if (opt.on_impostors) opt.on_impostors(g, ir);
  }

  progress.stage("writing package");
  const std::vector<std::string> bad = graph::checkInvariants(g);
  if (!bad.empty()) throw core::Error(core::Status::Internal, "street graph invariant broken: " + bad.front());
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
  hdr.max_block_blob_bytes = max_blob;
  hdr.source_bytes = city.source_bytes;
  writer.setHeader(hdr);
  writer.addSection(package::kSectionGraph, graph::serializeGraph(g));
  writer.addSection(package::kSectionCells, graph::serializeCells(g));
  writer.addSection(package::kSectionBlocks, graph::serializeBlocks(blocks));
  if (!tables.visibility.empty()) {
    writer.addSection(package::kSectionVisibility, graph::serializeVisibility(tables));
    writer.addSection(package::kSectionImpostors, graph::serializeImpostors(tables));
  }
  nlohmann::json meta = {
      {"generator", "blvd bake"},
      {"source", osm_path.substr(osm_path.find_last_of('/') + 1)},
      {"attribution", "© OpenStreetMap contributors (ODbL 1.0)"},
      {"default_height_m", opt.osm.default_height_m},
      {"level_height_m", opt.osm.level_height_m},
      {"draco", opt.draco},
      {"impostors",
       {{"mode", opt.impostor.mode == ImpostorMode::None     ? "none"
                 : opt.impostor.mode == ImpostorMode::Single ? "single"
                 : opt.impostor.mode == ImpostorMode::Both   ? "both"
                                                             : "layered"},
        {"threshold_px", opt.impostor.threshold_px},
        {"texture_max", opt.impostor.texture_max},
        {"grid_px", opt.impostor.grid_px},
        {"display", {opt.impostor.display_width, opt.impostor.display_height, opt.impostor.display_fov_y_deg}}}},
      {"counts",
       {{"streets", sum.streets}, {"buildings", sum.buildings}, {"height_tagged", city.height_tagged},
        {"level_tagged", city.level_tagged}, {"defaulted", city.defaulted}, {"skipped", sum.skipped_buildings}}},
  };
  const std::string meta_text = meta.dump(1);
  writer.addSection(package::kSectionMeta, std::vector<uint8_t>(meta_text.begin(), meta_text.end()));
  writer.write(out_path);
  sum.package_bytes = writer.fileBytes();
  progress.finish();

  sum.junctions = g.junctionCount();
  sum.vertices = g.vertices.size();
  sum.cells = g.cellCount();
  sum.blocks = g.faces.size();
  sum.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return sum;
}

}  // namespace blvd::bake
