#include "cli/bake_report.h"

#include <sys/stat.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>

#include "cli/report.h"
#include "core/status.h"

namespace blvd::cli {
namespace {
void writeFile(const std::string& path, const void* data, size_t n) {
  std::ofstream f(path, std::ios::binary);
  if (!f.write(static_cast<const char*>(data), static_cast<std::streamsize>(n)))
    throw core::Error(core::Status::Io, path + ": cannot write");
}
std::string fmt(double v, int decimals) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", decimals, v);
  return b;
}
}  // namespace

void writeBakeReport(const std::string& dir, const std::string& source, const graph::StreetGraph& g,
                     const bake::ImpostorBakeResult& r, const bake::LodStats& lod) {
  ::mkdir(dir.c_str(), 0755);
  ::mkdir((dir + "/thumbs").c_str(), 0755);

  // Map: one line per undirected street, coloured by the larger layer count of its two cells.
  size_t max_layers = 1;
  for (const auto& c : r.tables.impostors) max_layers = std::max(max_layers, c.layered.size());
  MapSpec map;
  map.title = "Street graph: cells coloured by impostor layers";
  for (uint32_t h = 0; h < g.halfedges.size(); ++h) {
    const auto& e = g.halfedges[h];
    if (h > e.twin) continue;
    size_t layers = 0;
    bool baked = false;
    for (uint32_t c : {h, e.twin})
      if (c < r.tables.impostors.size()) {
        layers = std::max(layers, r.tables.impostors[c].layered.size());
        baked |= !r.tables.impostors[c].layered.empty() || !r.tables.impostors[c].single.empty();
      }
    MapLine line;
    for (uint32_t i = 0; i < e.pts_count; ++i) line.pts.emplace_back(g.points[e.pts_begin + i].x, g.points[e.pts_begin + i].y);
    line.color = layers ? colorRamp(double(layers) / double(max_layers)) : (baked ? "#999999" : "#dddddd");
    line.width = layers ? 2.0 : 1.0;
    map.lines.push_back(std::move(line));
  }
  for (size_t l = 1; l <= max_layers; ++l)
    map.legend.push_back({std::to_string(l) + (l == 1 ? " layer" : " layers"), colorRamp(double(l) / double(max_layers))});
  map.legend.push_back({"no impostor", "#dddddd"});
  const std::string map_svg = svgMap(map);
  writeFile(dir + "/map.svg", map_svg.data(), map_svg.size());

  // Statistics.
  std::map<size_t, size_t> layer_hist;
  for (const auto& c : r.tables.impostors)
    if (!c.layered.empty()) ++layer_hist[c.layered.size()];
  double tri = 0, bytes = 0, secs = 0;
  for (const auto& rec : r.records) tri += rec.triangles, bytes += rec.bytes, secs += rec.seconds;
  const double n = std::max<size_t>(1, r.records.size());

  HtmlPage page("blvd bake report: " + source);
  page.paragraph("Map data © OpenStreetMap contributors (ODbL).");
  page.h2("Summary");
  std::vector<std::vector<std::string>> rows = {{"quantity", "value"}};
  rows.push_back({"item-buffer samples (PVS + coverage hints)", std::to_string(r.samples)});
  rows.push_back({"PVS time, s", fmt(r.pvs_seconds, 1)});
  rows.push_back({"impostor meshes", std::to_string(r.records.size())});
  rows.push_back({"impostor time, s", fmt(r.impostor_seconds, 1)});
  rows.push_back({"mean triangles per impostor", fmt(tri / n, 0)});
  rows.push_back({"mean bytes per impostor (GLB: Draco mesh + JPEG)", fmt(bytes / n, 0)});
  rows.push_back({"mean bake time per impostor, ms", fmt(1000 * secs / n, 1)});
  rows.push_back({"cells whose layering exceeded the cap (merged)", std::to_string(r.capped_cells)});
  rows.push_back({"largest visibility-event weight admitted by a merge, px", fmt(r.capped_worst_px, 1)});
  // Where a cap bit the texture density (docs/decisions/0010).
  size_t dense = 0, capped = 0;
  for (const auto& rec : r.records) (rec.density >= 0.999 ? dense : capped)++;
  rows.push_back({"impostors at one texel per display pixel (at the vantage point)", std::to_string(dense)});
  rows.push_back({"impostors below it (--texture or --cell-texels bit; see \"density\" below)", std::to_string(capped)});
  rows.push_back({"cells the texel budget scaled down (--cell-texels)", std::to_string(r.budget_cells)});
  rows.push_back({"lowest density the budget left, texels per display pixel", fmt(r.budget_min_density, 2)});
  for (const auto& [layers, cells] : layer_hist)
    rows.push_back({"cells with " + std::to_string(layers) + " layer(s)", std::to_string(cells)});
  page.table(rows);
  page.h2("Block levels of detail");
  std::vector<std::vector<std::string>> lods = {{"level", "blocks", "triangles", "vertices"}};
  for (uint32_t k = 0; k < graph::kMaxBlockLods; ++k)
    lods.push_back({std::to_string(k), std::to_string(lod.blocks[k]), std::to_string(lod.triangles[k]),
                    std::to_string(lod.vertices[k])});
  page.table(lods);
  page.paragraph("Simplified levels made by meshopt_simplifySloppy: " + std::to_string(lod.sloppy_levels) +
                 "; with the border unlocked: " + std::to_string(lod.unlocked_levels) +
                 "; largest error " + fmt(lod.max_error_m, 2) + " m; simplification " + fmt(lod.seconds, 2) + " s.");
  page.h2("Map");
  page.raw(map_svg);

  // Thumbnails: the first 48 impostors, and a table of all of them.
  page.h2("Impostor textures");
  std::vector<Figure> figs;
  for (size_t i = 0; i < r.records.size() && figs.size() < 48; ++i) {
    const auto& rec = r.records[i];
    const std::string name = "thumbs/cell" + std::to_string(rec.cell) + (rec.single ? "_single" : "_layer" + std::to_string(rec.layer)) + ".jpg";
    writeFile(dir + "/" + name, rec.jpeg.data(), rec.jpeg.size());
    figs.push_back({name, "cell " + std::to_string(rec.cell) + (rec.single ? " single" : " layer " + std::to_string(rec.layer)) +
                              ": " + std::to_string(rec.triangles) + " tris, " + std::to_string(rec.bytes / 1024) + " KiB, " +
                              std::to_string(rec.texture_width) + "x" + std::to_string(rec.texture_height)});
  }
  page.imageGrid(figs, 4);
  page.h2("Every impostor");
  std::vector<std::vector<std::string>> all = {
      {"cell", "kind", "layer", "run from, m", "captures", "blocks", "triangles", "bytes", "texture", "density", "ms"}};
  for (const auto& rec : r.records)
    all.push_back({std::to_string(rec.cell), rec.single ? "single" : "layered", std::to_string(rec.layer),
                   fmt(rec.run_from_m, 0), std::to_string(rec.shot), std::to_string(rec.blocks),
                   std::to_string(rec.triangles), std::to_string(rec.bytes),
                   std::to_string(rec.texture_width) + "x" + std::to_string(rec.texture_height), fmt(rec.density, 2),
                   fmt(1000 * rec.seconds, 1)});
  page.table(all);
  std::string err;
  if (!page.write(dir + "/index.html", err)) throw core::Error(core::Status::Io, err);
}

}  // namespace blvd::cli
