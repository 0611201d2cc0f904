#include <gtest/gtest.h>

#include <cstring>
#include <limits>

#include <glm/geometric.hpp>

#include "core/status.h"
#include "graph/block_table.h"
#include "graph/cell_tables.h"
#include "graph/street_graph.h"

using namespace blvd;

namespace {
// A triangle of streets built by hand (no CGAL, so this parser test stays
// light enough to run under ASan + UBSan in CI): A(0,0) B(100,0) C(0,100);
// half-edges AB BA BC CB CA AC; face 1 is the block inside, face 0 outside.
graph::StreetGraph smallGraph() {
  graph::StreetGraph g;
  g.vertices = {{{0, 0}, graph::VertexKind::Junction, 0},
                {{100, 0}, graph::VertexKind::Junction, 2},
                {{0, 100}, graph::VertexKind::Junction, 4}};
  const uint32_t origin[6] = {0, 1, 1, 2, 2, 0}, next[6] = {2, 5, 4, 1, 0, 3}, face[6] = {1, 0, 1, 0, 1, 0};
  for (uint32_t h = 0; h < 6; ++h) {
    graph::HalfEdge e;
    e.origin = origin[h];
    e.twin = h ^ 1u;
    e.next = next[h];
    e.face = face[h];
    e.pts_begin = static_cast<uint32_t>(g.points.size());
    e.pts_count = 2;
    e.road_class = graph::RoadClass::Residential;
    e.width = 7;
    e.osm_way = 100 + h / 2;
    g.points.push_back(g.vertices[origin[h]].p);
    g.points.push_back(g.vertices[origin[h ^ 1u]].p);
    e.length = static_cast<float>(glm::length(g.points.back() - g.points[e.pts_begin]));
    g.halfedges.push_back(e);
  }
  g.faces = {{1, true, 0}, {0, false, 5000}};
  for (uint32_t h = 0; h < 6; ++h) {
    g.successors.push({g.halfedges[h].next});
    g.local_blocks.push({0, 1});
  }
  std::vector<std::vector<uint32_t>> pred(6);
  for (uint32_t h = 0; h < 6; ++h) pred[g.halfedges[h].next].push_back(h);
  for (const auto& p : pred) g.predecessors.push(p);
  return g;
}
}  // namespace

TEST(GraphSerialize, HandMadeGraphIsValid) {
  const auto bad = graph::checkInvariants(smallGraph());
  EXPECT_TRUE(bad.empty()) << bad.front();
}

TEST(GraphSerialize, CellTablesRoundTripAndRejectBadIndices) {
  graph::CellTables t;
  t.threshold_px = 10;
  t.display_fov_y_deg = 45;
  t.display_width = 800;
  t.display_height = 480;
  t.visibility.resize(6);
  t.impostors.resize(6);
  t.visibility[2] = {{0, 1}, {0.25f, 0.5f}};
  graph::ImpostorLayer layer;
  layer.blob = 3;
  layer.triangles = 77;
  layer.vertices = 231;
  layer.texture_width = 512;
  layer.texture_height = 128;
  layer.blocks = {0};
  t.impostors[2].layered = {layer, layer};
  t.impostors[2].layered[1].run_from_m = 40.f;  // a second run, 40 m into the cell
  t.impostors[4].single = {layer};
  const std::vector<float> len(6, 100.f);
  const auto vb = graph::serializeVisibility(t), ib = graph::serializeImpostors(t);
  graph::CellTables r;
  graph::parseVisibility(vb.data(), vb.size(), 0, 6, 2, r);
  graph::parseImpostors(ib.data(), ib.size(), 0, len, 2, 4, r);
  EXPECT_EQ(r.visibility[2].blocks, t.visibility[2].blocks);
  EXPECT_EQ(r.visibility[2].ach, t.visibility[2].ach);
  ASSERT_EQ(r.impostors[2].layered.size(), 2u);
  EXPECT_EQ(r.impostors[2].layered[1].run_from_m, 40.f);
  EXPECT_EQ(r.impostors[2].layered[0].triangles, 77u);
  EXPECT_EQ(r.impostors[2].layered[0].vertices, 231u);
  EXPECT_EQ(r.impostors[4].single[0].texture_width, 512);
  EXPECT_EQ(r.threshold_px, 10.f);
  // A blob index past the package's blobs, a block past its blocks, and every truncation.
  EXPECT_THROW(graph::parseImpostors(ib.data(), ib.size(), 0, len, 2, 3, r), core::Error);
  // A run past the cell's end, or out of order.
  const std::vector<float> short_cells(6, 30.f);
  EXPECT_THROW(graph::parseImpostors(ib.data(), ib.size(), 0, short_cells, 2, 4, r), core::Error);
  t.impostors[2].layered = {t.impostors[2].layered[1], layer};
  const auto unordered = graph::serializeImpostors(t);
  EXPECT_THROW(graph::parseImpostors(unordered.data(), unordered.size(), 0, len, 2, 4, r), core::Error);
  EXPECT_THROW(graph::parseVisibility(vb.data(), vb.size(), 0, 6, 1, r), core::Error);
  EXPECT_THROW(graph::parseVisibility(vb.data(), vb.size(), 0, 7, 2, r), core::Error);
  for (size_t n = 0; n < ib.size(); ++n) EXPECT_THROW(graph::parseImpostors(ib.data(), n, 0, len, 2, 4, r), core::Error);
  for (size_t n = 0; n < vb.size(); ++n) EXPECT_THROW(graph::parseVisibility(vb.data(), n, 0, 6, 2, r), core::Error);
}

TEST(GraphSerialize, RoundTrip) {
  const graph::StreetGraph g = smallGraph();
  const auto gb = graph::serializeGraph(g), cb = graph::serializeCells(g);
  graph::StreetGraph r;
  graph::parseGraph(gb.data(), gb.size(), 0, r);
  graph::parseCells(cb.data(), cb.size(), 0, r);
  ASSERT_EQ(r.vertices.size(), g.vertices.size());
  ASSERT_EQ(r.halfedges.size(), g.halfedges.size());
  for (size_t i = 0; i < g.halfedges.size(); ++i) {
    EXPECT_EQ(r.halfedges[i].twin, g.halfedges[i].twin);
    EXPECT_EQ(r.halfedges[i].next, g.halfedges[i].next);
    EXPECT_EQ(r.halfedges[i].face, g.halfedges[i].face);
    EXPECT_EQ(r.halfedges[i].osm_way, g.halfedges[i].osm_way);
  }
  EXPECT_EQ(r.points, g.points);
  EXPECT_EQ(r.successors.items, g.successors.items);
  EXPECT_EQ(r.local_blocks.offsets, g.local_blocks.offsets);
  EXPECT_TRUE(graph::checkInvariants(r).empty());
}

TEST(GraphSerialize, EveryTruncationAndByteFlipIsCaught) {
  const graph::StreetGraph g = smallGraph();
  const auto gb = graph::serializeGraph(g);
  for (size_t n = 0; n < gb.size(); ++n) {
    graph::StreetGraph r;
    EXPECT_THROW(graph::parseGraph(gb.data(), n, 100, r), core::Error) << "length " << n;
  }
  // Flipping any byte either is caught or yields a graph whose indices are in range.
  for (size_t i = 0; i < gb.size(); ++i) {
    auto bad = gb;
    bad[i] ^= 0xff;
    graph::StreetGraph r;
    try {
      graph::parseGraph(bad.data(), bad.size(), 0, r);
      for (const auto& h : r.halfedges) {
        ASSERT_LT(h.twin, r.halfedges.size());
        ASSERT_LE(h.pts_begin + h.pts_count, r.points.size());
      }
    } catch (const core::Error& e) {
      EXPECT_EQ(e.status(), core::Status::Corrupt);
    }
  }
  const auto cb = graph::serializeCells(g);
  for (size_t n = 0; n < cb.size(); ++n) {
    graph::StreetGraph r = g;
    EXPECT_THROW(graph::parseCells(cb.data(), n, 0, r), core::Error);
  }
}

// Three blocks: empty, one level, three levels.
std::vector<graph::BlockRecord> sampleBlocks() {
  std::vector<graph::BlockRecord> blocks(3);
  blocks[1].blob = 0;
  blocks[1].lod_count = 1;
  blocks[1].triangles[0] = blocks[1].triangle_count = 12;
  blocks[1].vertices[0] = blocks[1].vertex_count = 24;
  blocks[1].bbox_max[1] = 9.5f;
  graph::BlockRecord& b = blocks[2];
  b.blob = 7;
  b.building_count = 4;
  b.flags = graph::kBlockUnbounded;
  b.lod_count = 3;
  const uint32_t tris[3] = {1000, 480, 90}, verts[3] = {2000, 700, 150};
  const float err[3] = {0.f, 0.25f, 1.5f};
  for (int k = 0; k < 3; ++k) b.triangles[k] = tris[k], b.vertices[k] = verts[k], b.error_m[k] = err[k];
  b.triangle_count = 1000;
  b.vertex_count = 2000;
  for (int k = 0; k < 3; ++k) b.bbox_min[k] = -1.f - k, b.bbox_max[k] = 2.f + k;
  return blocks;
}

TEST(GraphSerialize, BlockTableRoundTripsLevels) {
  const auto blocks = sampleBlocks();
  const auto bytes = graph::serializeBlocks(blocks);
  std::vector<graph::BlockRecord> r;
  graph::parseBlocks(bytes.data(), bytes.size(), 0, 8, r);
  ASSERT_EQ(r.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(r[i].blob, blocks[i].blob);
    EXPECT_EQ(r[i].building_count, blocks[i].building_count);
    EXPECT_EQ(r[i].flags, blocks[i].flags);
    EXPECT_EQ(r[i].lod_count, blocks[i].lod_count);
    EXPECT_EQ(r[i].triangle_count, blocks[i].triangle_count);
    EXPECT_EQ(r[i].vertex_count, blocks[i].vertex_count);
    for (uint32_t k = 0; k < graph::kMaxBlockLods; ++k) {
      EXPECT_EQ(r[i].triangles[k], blocks[i].triangles[k]);
      EXPECT_EQ(r[i].vertices[k], blocks[i].vertices[k]);
      EXPECT_EQ(r[i].error_m[k], blocks[i].error_m[k]);
    }
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(r[i].bbox_min[k], blocks[i].bbox_min[k]);
      EXPECT_EQ(r[i].bbox_max[k], blocks[i].bbox_max[k]);
    }
  }
  EXPECT_EQ(r[2].allTriangles(), 1570u);
  EXPECT_EQ(r[2].allVertices(), 2850u);
  EXPECT_EQ(r[0].allTriangles(), 0u);
}

TEST(GraphSerialize, BlockTableChecksBlobIndex) {
  const auto b = graph::serializeBlocks(sampleBlocks());
  std::vector<graph::BlockRecord> r;
  try {
    graph::parseBlocks(b.data(), b.size(), 512, 5, r);
    FAIL();
  } catch (const core::Error& e) {
    EXPECT_EQ(e.status(), core::Status::Corrupt);
    // Block 2's record starts at 12 + 2 * 88 bytes into the section.
    EXPECT_NE(std::string(e.what()).find("BLCK at offset " + std::to_string(512 + 12 + 2 * 88)), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("blob index out of range"), std::string::npos) << e.what();
  }
}

TEST(GraphSerialize, BlockTableRefusesBrokenLevels) {
  auto expectRefused = [](std::vector<graph::BlockRecord> blocks, const char* why) {
    EXPECT_THROW(graph::serializeBlocks(blocks), core::Error) << why;
    // Write a good table, then patch the record bytes so the parser sees the bad one.
    const auto good = graph::serializeBlocks(sampleBlocks());
    auto bad = good;
    const size_t rec = 12 + 2 * 88;
    const graph::BlockRecord& b = blocks[2];
    std::memcpy(&bad[rec + 12], &b.lod_count, 4);
    std::memcpy(&bad[rec + 40], b.triangles, 16);
    std::memcpy(&bad[rec + 56], b.vertices, 16);
    std::memcpy(&bad[rec + 72], b.error_m, 16);
    std::vector<graph::BlockRecord> r;
    try {
      graph::parseBlocks(bad.data(), bad.size(), 0, 8, r);
      ADD_FAILURE() << why << ": parsed";
    } catch (const core::Error& e) {
      EXPECT_EQ(e.status(), core::Status::Corrupt);
      EXPECT_NE(std::string(e.what()).find("offset " + std::to_string(rec)), std::string::npos) << e.what();
    }
  };
  const std::pair<const char*, void (*)(graph::BlockRecord&)> cases[] = {
      {"a level without fewer triangles", [](graph::BlockRecord& b) { b.triangles[2] = 480; }},
      {"a decreasing error", [](graph::BlockRecord& b) { b.error_m[2] = 0.1f; }},
      {"a NaN error", [](graph::BlockRecord& b) { b.error_m[1] = std::numeric_limits<float>::quiet_NaN(); }},
      {"five levels", [](graph::BlockRecord& b) { b.lod_count = 5; }},
      {"counts past lod_count", [](graph::BlockRecord& b) { b.triangles[3] = 5; }},
      {"an error on level 0", [](graph::BlockRecord& b) { b.error_m[0] = 0.5f; }},
      {"a level without vertices", [](graph::BlockRecord& b) { b.vertices[1] = 0; }},
      {"more vertices than the decoder gives",
       [](graph::BlockRecord& b) { b.vertices[0] = b.vertex_count = (1u << 24) + 1; }},
  };
  for (const auto& [why, mutate] : cases) {
    auto blocks = sampleBlocks();
    mutate(blocks[2]);
    expectRefused(blocks, why);
  }
}

TEST(GraphSerialize, BlockTableEveryTruncationAndFlipIsClean) {
  const auto b = graph::serializeBlocks(sampleBlocks());
  std::vector<graph::BlockRecord> r;
  for (size_t n = 0; n < b.size(); ++n) EXPECT_THROW(graph::parseBlocks(b.data(), n, 0, 8, r), core::Error) << n;
  auto longer = b;
  longer.push_back(0);
  EXPECT_THROW(graph::parseBlocks(longer.data(), longer.size(), 0, 8, r), core::Error);
  for (size_t i = 0; i < b.size(); ++i) {
    auto bad = b;
    bad[i] ^= 0x5a;
    try {
      graph::parseBlocks(bad.data(), bad.size(), 0, 8, r);
      for (const auto& x : r) {  // what parses keeps the rules
        ASSERT_LE(x.lod_count, graph::kMaxBlockLods);
        for (uint32_t k = 1; k < x.lod_count; ++k) ASSERT_LT(x.triangles[k], x.triangles[k - 1]);
      }
    } catch (const core::Error& e) {
      EXPECT_EQ(e.status(), core::Status::Corrupt);
    }
  }
  // A table from before the levels of detail (record version 1) is refused by name.
  auto v1 = b;
  v1[0] = 1;
  try {
    graph::parseBlocks(v1.data(), v1.size(), 64, 8, r);
    FAIL();
  } catch (const core::Error& e) {
    EXPECT_NE(std::string(e.what()).find("block record version 1"), std::string::npos) << e.what();
  }
}
