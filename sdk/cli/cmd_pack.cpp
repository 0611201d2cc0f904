#include <algorithm>
#include <cstdio>
#include <fstream>
#include <memory>

#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "package/glb.h"
#include "stream/city.h"

namespace blvd::cli {
namespace {

std::unique_ptr<stream::City> openCity(const std::string& path) {
  auto city = std::make_unique<stream::City>();
  std::string err;
  const core::Status st = city->open(path, err);
  if (st != core::Status::Ok) throw core::Error(st, err);
  return city;
}

int info(const std::string& path, bool json) {
  const auto opened = openCity(path);
  const stream::City& city = *opened;
  const auto& h = city.header();
  const auto& g = city.graph();
  nlohmann::json j = {
      {"file", path},
      {"bytes", city.package().fileSize()},
      {"version", std::to_string(h.version_major) + "." + std::to_string(h.version_minor)},
      {"origin", {{"lat", h.origin_lat}, {"lon", h.origin_lon}}},
      {"bounds_m", {{"min", {h.bounds_min[0], h.bounds_min[1]}}, {"max", {h.bounds_max[0], h.bounds_max[1]}}}},
      {"counts",
       {{"junctions", h.junction_count}, {"graph_vertices", g.vertices.size()}, {"cells", h.cell_count},
        {"blocks", h.block_count}, {"buildings", h.building_count}, {"triangles", h.triangle_count},
        {"blobs", city.package().blobCount()}}},
      {"max_block_blob_bytes", h.max_block_blob_bytes},
      {"source_bytes", h.source_bytes},
  };
  // Blobs as stored and as their contents (package 4.0 keeps most as zstd frames).
  uint64_t stored = 0, contents = 0, frames = 0;
  for (uint32_t i = 0; i < city.package().blobCount(); ++i) {
    const package::BlobInfo& b = city.package().blobInfo(i);
    stored += b.size;
    contents += b.contents_size;
    frames += (b.flags & package::kBlobZstd) != 0;
  }
  j["blob_bytes"] = {{"stored", stored}, {"contents", contents}, {"zstd_frames", frames}};
  // Levels of detail, from the BLCK records (no decoding).
  nlohmann::json levels = nlohmann::json::array();
  for (uint32_t k = 0; k < graph::kMaxBlockLods; ++k) {
    uint64_t blocks = 0, tris = 0, verts = 0;
    double max_err = 0, sum_err = 0;
    for (const graph::BlockRecord& b : city.blocks()) {
      if (k >= b.lod_count) continue;
      ++blocks;
      tris += b.triangles[k];
      verts += b.vertices[k];
      max_err = std::max(max_err, double(b.error_m[k]));
      sum_err += b.error_m[k];
    }
    levels.push_back({{"level", k}, {"blocks", blocks}, {"triangles", tris}, {"vertices", verts},
                      {"max_error_m", max_err}, {"mean_error_m", blocks ? sum_err / double(blocks) : 0.0}});
  }
  j["lod_levels"] = levels;
  nlohmann::json pools = nlohmann::json::object();
  for (const package::PoolSizingField& f : package::poolSizing(h)) pools[f.name] = f.value;
  j["pool_sizing"] = pools;
  // The bake's metadata (options, LOD totals, tiling, the impostor route).
  package::Span meta;
  std::vector<uint8_t> meta_bytes;
  std::string meta_err;
  if (city.package().hasSection(package::kSectionMeta) &&
      city.package().checkedCopy(package::kSectionMeta, meta_bytes, meta, meta_err) == core::Status::Ok)
    j["meta"] = nlohmann::json::parse(meta.data, meta.data + meta.size, nullptr, false);
  nlohmann::json sections = nlohmann::json::object();
  for (const auto& s : city.package().sections())
    sections[package::tagToString(s.tag)] = {{"offset", s.offset}, {"bytes", s.size}};
  j["sections"] = sections;
  if (json) {
    std::printf("%s\n", j.dump(2).c_str());
    return 0;
  }
  std::printf("%s: blvd package %s, %llu bytes\n", path.c_str(), j["version"].get<std::string>().c_str(),
              static_cast<unsigned long long>(city.package().fileSize()));
  std::printf("  origin %.7f, %.7f; bounds %.0f x %.0f m\n", h.origin_lat, h.origin_lon,
              double(h.bounds_max[0] - h.bounds_min[0]), double(h.bounds_max[1] - h.bounds_min[1]));
  std::printf("  junctions %u, cells %u, blocks %u, buildings %u, triangles %llu\n", h.junction_count, h.cell_count,
              h.block_count, h.building_count, static_cast<unsigned long long>(h.triangle_count));
  std::printf("  pool sizing (header):\n");
  for (const auto& [key, value] : j["pool_sizing"].items())
    std::printf("    %-32s %llu\n", key.c_str(), value.get<unsigned long long>());
  std::printf("  levels of detail:\n");
  for (const auto& l : levels)
    std::printf("    level %u: %6llu blocks, %9llu triangles, %9llu vertices, error mean %.2f m, max %.2f m\n",
                l["level"].get<unsigned>(), l["blocks"].get<unsigned long long>(),
                l["triangles"].get<unsigned long long>(), l["vertices"].get<unsigned long long>(),
                l["mean_error_m"].get<double>(), l["max_error_m"].get<double>());
  std::printf("  sections:\n");
  for (const auto& s : city.package().sections())
    std::printf("    %-4s  offset %10llu  %10llu bytes\n", package::tagToString(s.tag).c_str(),
                static_cast<unsigned long long>(s.offset), static_cast<unsigned long long>(s.size));
  return 0;
}

int verify(const std::string& path) {
  package::PackageReader r;
  std::string err;
  core::Status st = package::PackageReader::open(path, r, err);
  if (st == core::Status::Ok) st = r.verify(err);
  if (st == core::Status::Ok) {
    // The sections must also parse (bounds and index checks), not only match their CRCs:
    // whole, as the tools read them, and paged, as the runtime does (SIDX, CTIX).
    stream::City city, paged;
    st = city.open(path, err);
    if (st == core::Status::Ok)
      st = paged.open(path, err, stream::City::Tables::All, stream::City::GraphTables::Paged);
    // And every blob stored as a zstd frame must give back its contents.
    std::vector<uint8_t> contents;
    package::Span s;
    for (uint32_t i = 0; st == core::Status::Ok && i < r.blobCount(); ++i) st = r.blobContents(i, contents, s, err);
  }
  if (st != core::Status::Ok) {
    std::fprintf(stderr, "blvd pack verify: %s\n", err.c_str());
    return 1;
  }
  std::printf("%s: ok (%u blobs, every checksum matches, every frame decompresses)\n", path.c_str(), r.blobCount());
  return 0;
}

// Layered impostor layer `layer` of `cell` (counted as `pack cell` lists
// them), decoded: its depth mesh in the package frame, with its texture.
std::vector<uint8_t> impostorGlb(const stream::City& city, int cell, int layer) {
  std::vector<stream::LayerInfo> layers(city.maxCellLayers());
  uint32_t layered = 0, single = 0;
  city.cellLayers(uint32_t(cell), layers.data(), uint32_t(layers.size()), &layered, &single);
  if (layer < 0 || uint32_t(layer) >= layered)
    throw core::Error(core::Status::NotFound, "cell " + std::to_string(cell) + " has " + std::to_string(layered) +
                                                  " layered impostor layers, not " + std::to_string(layer));
  geo::MeshData mesh;
  std::string err;
  const core::Status st = city.decodeImpostorBlob(layers[size_t(layer)].blob, mesh, err);
  if (st != core::Status::Ok) throw core::Error(st, err);
  package::GlbOptions plain;
  plain.codec = package::GlbCodec::Plain;
  return package::encodeGlb(mesh, plain);
}

int extract(const std::string& path, int block, int cell, int layer, const std::string& out) {
  const auto opened = openCity(path);
  const stream::City& city = *opened;
  std::vector<uint8_t> glb;
  std::string err;
  if (block >= 0) {
    if (static_cast<size_t>(block) >= city.blocks().size())
      throw core::Error(core::Status::NotFound, "block " + std::to_string(block) + " does not exist (" +
                                                    std::to_string(city.blocks().size()) + " blocks)");
    const uint32_t blob = city.blocks()[block].blob;
    if (blob == 0xffffffffu) throw core::Error(core::Status::NotFound, "block " + std::to_string(block) + " is empty");
    package::Span s;
    const core::Status st = city.package().readBlobContents(blob, glb, s, err);
    if (st != core::Status::Ok) throw core::Error(st, err);
    glb.resize(s.size);  // already a GLB (decompressed when stored as a zstd frame): extracted byte for byte
  } else {
    const auto& g = city.graph();
    if (cell < 0 || static_cast<size_t>(cell) >= g.cellCount())
      throw core::Error(core::Status::NotFound, "cell " + std::to_string(cell) + " does not exist (" +
                                                    std::to_string(g.cellCount()) + " cells)");
    if (layer >= 0) {
      glb = impostorGlb(city, cell, layer);
    } else {
      geo::MeshData all, one;
      for (const uint32_t* b = g.local_blocks.begin(cell); b != g.local_blocks.end(cell); ++b) {
        const core::Status st = city.decodeBlock(*b, one, err);
        if (st != core::Status::Ok) throw core::Error(st, err);
        all.append(one);
      }
      glb = package::encodeGlb(all);
    }
  }
  std::ofstream f(out, std::ios::binary);
  if (!f.write(reinterpret_cast<const char*>(glb.data()), static_cast<std::streamsize>(glb.size())))
    throw core::Error(core::Status::Io, out + ": cannot write");
  std::printf("wrote %s (%zu bytes)\n", out.c_str(), glb.size());
  return 0;
}

// One cell as the runtime sees it: its street, local model, PVS with
// coverage hints, and impostor layers with the blocks each stands for.
int cellInfo(const std::string& path, int cell) {
  const auto opened = openCity(path);
  const stream::City& city = *opened;
  const auto& g = city.graph();
  if (cell < 0 || size_t(cell) >= g.cellCount())
    throw core::Error(core::Status::NotFound, "cell " + std::to_string(cell) + " does not exist (" +
                                                  std::to_string(g.cellCount()) + " cells)");
  const graph::HalfEdge& e = g.halfedges[size_t(cell)];
  const glm::dvec2 a = g.points[e.pts_begin], b = g.points[e.pts_begin + e.pts_count - 1];
  nlohmann::json j = {{"cell", cell},
                      {"length_m", e.length},
                      {"from", {a.x, a.y}},
                      {"to", {b.x, b.y}},
                      {"polyline_points", e.pts_count},
                      {"local_blocks", std::vector<uint32_t>(g.local_blocks.begin(size_t(cell)),
                                                             g.local_blocks.end(size_t(cell)))}};
  const auto& t = city.cellTables();
  if (size_t(cell) < t.visibility.size()) {
    nlohmann::json pvs = nlohmann::json::array();
    const auto& v = t.visibility[size_t(cell)];
    for (size_t k = 0; k < v.blocks.size(); ++k) pvs.push_back({v.blocks[k], v.ach[k]});
    j["pvs_block_ach"] = pvs;
  }
  if (size_t(cell) < t.impostors.size()) {
    for (const char* kind : {"layered", "single"}) {
      const auto& layers = std::string(kind) == "single" ? t.impostors[size_t(cell)].single
                                                          : t.impostors[size_t(cell)].layered;
      nlohmann::json arr = nlohmann::json::array();
      for (const auto& l : layers)
        arr.push_back({{"run_from_m", l.run_from_m},
                       {"blocks", l.blocks},
                       {"triangles", l.triangles},
                       {"texture", {l.texture_width, l.texture_height}}});
      j[kind] = arr;
    }
  }
  std::printf("%s\n", j.dump(2).c_str());
  return 0;
}

}  // namespace

void addPack(CLI::App& app, Runner& run) {
  auto* pack = app.add_subcommand("pack", "inspect, verify or extract from a package; merge bake shards");
  pack->require_subcommand(1);
  auto path = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  auto* info_cmd = pack->add_subcommand("info", "counts and bytes per section");
  info_cmd->add_option("package", *path)->required();
  info_cmd->add_flag("--json", *json, "machine-readable output");
  info_cmd->callback([&run, path, json] { run = [path, json] { return info(*path, *json); }; });

  auto* verify_cmd = pack->add_subcommand("verify", "check every checksum; exit 1 naming the bad section and offset");
  verify_cmd->add_option("package", *path)->required();
  verify_cmd->callback([&run, path] { run = [path] { return verify(*path); }; });

  auto block = std::make_shared<int>(-1), cell = std::make_shared<int>(-1);
  auto* cell_cmd = pack->add_subcommand("cell", "one cell as JSON: street, local blocks, PVS with coverage, impostor layers");
  cell_cmd->add_option("package", *path)->required();
  cell_cmd->add_option("cell", *cell, "cell index")->required();
  cell_cmd->callback([&run, path, cell] { run = [path, cell] { return cellInfo(*path, *cell); }; });

  auto out = std::make_shared<std::string>();
  auto* ex = pack->add_subcommand("extract", "write one block's or one cell's local model as a GLB");
  ex->add_option("package", *path)->required();
  auto* ob = ex->add_option("--block", *block, "block index");
  auto* oc = ex->add_option("--cell", *cell, "cell index (writes its local blocks)");
  auto layer = std::make_shared<int>(-1);
  auto* ol = ex->add_option("--layer", *layer, "with --cell: its layered impostor layer N instead (decoded, with its texture)");
  ob->excludes(oc);
  ol->needs(oc);
  ex->add_option("-o,--output", *out, "GLB file to write")->required();
  ex->callback([&run, path, block, cell, layer, out] {
    if (*block < 0 && *cell < 0) throw CLI::ValidationError("extract", "give --block N or --cell N");
    run = [path, block, cell, layer, out] { return extract(*path, *block, *cell, *layer, *out); };
  });
  addPackMerge(*pack, run);
}

}  // namespace blvd::cli
