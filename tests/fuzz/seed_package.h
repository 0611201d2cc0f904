// A small package with a street graph for the fuzz targets' seeds: a 3 x 3
// grid of streets 50 m apart (its cell lists and segment grid), one block with
// two levels, a PVS per cell and one impostor layer on cell 0 (a quad without
// its image), ground heights and terrain tiles.
#pragma once
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "graph/block_table.h"
#include "graph/cell_tables.h"
#include "graph/segment_grid.h"
#include "graph/street_graph.h"
#include "graph/terrain_table.h"
#include "package/glb.h"
#include "package/writer.h"
#include "track/track_test_util.h"

namespace blvd_test {

// A quad of two triangles with normals and colours.
inline blvd::geo::MeshData seedQuad() {
  blvd::geo::MeshData m;
  m.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  m.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
  m.colors.assign(16, 180);
  m.indices = {0, 1, 2, 2, 1, 3};
  return m;
}

inline blvd::package::PackageHeader seedHeader() {
  blvd::package::PackageHeader h;
  h.origin_lat = 43.73;
  h.origin_lon = 7.42;
  h.block_count = 2;
  return h;
}

// Fills the header's pool sizing from the tables (bake::fillPoolSizing's
// signature): what a package needs for blvd_runtime_create to open it.
using PoolSizer = std::function<void(const blvd::graph::StreetGraph&, const std::vector<blvd::graph::BlockRecord>&,
                                     const blvd::graph::CellTables&, const std::function<uint64_t(uint32_t)>&,
                                     blvd::package::PackageHeader&)>;

inline void writeGridPackage(const std::string& path, const PoolSizer& size_pools = {}) {
  using namespace blvd::package;
  const blvd::geo::MeshData m = seedQuad();
  PackageHeader h = seedHeader();
  // A small street graph, its cell lists and its segment grid.
  blvd::graph::StreetGraph g = blvd_test::makeGrid(3, 50);
  g.faces.resize(1);  // one block, all around: enough for the index checks to pass
  for (auto& e : g.halfedges) e.face = 0, e.next = e.next == blvd::graph::kNone ? e.twin : e.next;
  while (g.local_blocks.size() < g.halfedges.size()) g.local_blocks.push({0});
  blvd::graph::SegmentGrid grid;
  grid.build(g);
  PackageWriter gw;
  gw.setHeader(h);
  gw.setBlobCompression(19);  // as the bake stores blobs: zstd frames where they are smaller
  gw.addSection(kSectionGraph, blvd::graph::serializeGraph(g));
  gw.addSection(kSectionCells, blvd::graph::serializeCells(g));
  gw.addSection(kSectionSpatialIndex, blvd::graph::serializeSegmentGrid(grid));
  // One block whose blob holds two levels in meshopt (as the bake writes
  // blocks), and per-cell tables: a PVS of it and, on cell 0, one impostor
  // layer, a Draco quad with texture coordinates and no image.
  blvd::geo::MeshData coarse = m;
  coarse.indices.resize(3);
  GlbOptions meshopt;
  meshopt.codec = GlbCodec::Meshopt;
  std::vector<GlbMeshCounts> counts;
  blvd::graph::BlockRecord rec;
  rec.blob = gw.addBlob(encodeGlbLevels({m, coarse}, meshopt, &counts));
  rec.lod_count = 2;
  for (uint32_t k = 0; k < 2; ++k) rec.triangles[k] = counts[k].triangles, rec.vertices[k] = counts[k].vertices;
  rec.triangle_count = rec.triangles[0];
  rec.vertex_count = rec.vertices[0];
  rec.bbox_max[0] = rec.bbox_max[1] = rec.bbox_max[2] = 1;
  gw.addSection(kSectionBlocks, blvd::graph::serializeBlocks({rec}));
  blvd::geo::MeshData quad = m;
  quad.normals.clear();  // as an impostor's depth mesh
  quad.texcoords = {0, 0, 1, 0, 0, 1, 1, 1};
  GlbMeshCounts quad_counts;
  const uint32_t impostor_blob = gw.addBlob(encodeGlb(quad, {}, &quad_counts));
  blvd::graph::CellTables t;
  t.visibility.resize(g.halfedges.size(), blvd::graph::CellVisibility{{0}, {0.5f}});
  t.impostors.resize(g.halfedges.size());
  blvd::graph::ImpostorLayer layer;
  layer.blob = impostor_blob;
  layer.triangles = quad_counts.triangles;
  layer.vertices = quad_counts.vertices;
  layer.texture_width = layer.texture_height = 4;
  layer.blocks = {0};
  t.impostors[0].layered.push_back(layer);
  std::vector<uint64_t> vis_at, imp_at;
  gw.addSection(kSectionVisibility, blvd::graph::serializeVisibility(t, &vis_at));
  gw.addSection(kSectionImpostors, blvd::graph::serializeImpostors(t, &imp_at));
  gw.addSection(kSectionCellTableIndex, blvd::graph::serializeCellTableIndex(vis_at, imp_at));
  // The ground's heights (ELEV): a slope rising to the east.
  std::vector<uint8_t> elev(8 + 4 * g.points.size());
  const uint32_t head[2] = {1, static_cast<uint32_t>(g.points.size())};
  std::memcpy(elev.data(), head, 8);
  for (size_t i = 0; i < g.points.size(); ++i) {
    const float z = static_cast<float>(0.05 * g.points[i].x);
    std::memcpy(elev.data() + 8 + 4 * i, &z, 4);
  }
  gw.addSection(kSectionElevation, std::move(elev));
  // Terrain tiles (TERR): two levels of 3 x 3 heights over the grid.
  blvd::graph::TerrainLayout terrain;
  terrain.grid = 3, terrain.levels = 2, terrain.west = -50, terrain.south = -50, terrain.size = 200;
  terrain.base_m = 0, terrain.step_m = 0.01f, terrain.level_error_m[0] = 0.5f, terrain.level_error_m[1] = 0.5f;
  std::vector<blvd::graph::TerrainRecord> tiles(terrain.tiles());
  for (uint32_t i = 0; i < tiles.size(); ++i) {
    const float heights[9] = {0, 1, 2, 1, 2 + float(i), 3, 2, 3, 4};
    tiles[i] = blvd::graph::TerrainRecord{gw.addBlob(blvd::graph::encodeTerrainHeights(heights, terrain)), 0.5f, 0,
                                          4 + float(i)};
  }
  gw.addSection(kSectionTerrain, blvd::graph::serializeTerrain(terrain, tiles));
  if (size_pools) {
    size_pools(g, {rec}, t, [&](uint32_t i) { return uint64_t(gw.blob(i).size()); }, h);
    gw.setHeader(h);
  }
  gw.write(path);
}

}  // namespace blvd_test
