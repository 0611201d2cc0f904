// Per-block LOD chain (sdk/bake/lod_chain, block_blob): levels lose
// triangles, errors never decrease and stay finite, and the BLCK record's
// counts are exactly what decoding each level gives.
#include <gtest/gtest.h>

#include <cmath>

#include "bake/block_blob.h"
#include "bake/lod_chain.h"
#include "core/status.h"

namespace blvd::bake {
namespace {

// A bumpy 40 x 40 terrain (shared vertices) plus a row of flat-shaded boxes
// (24 vertices each): the two kinds of geometry a block has.
geo::MeshData blockLike() {
  geo::MeshData m;
  const int n = 40;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      m.positions.insert(m.positions.end(), {float(i), 0.3f * std::sin(i * 0.7f) * std::cos(j * 0.5f), float(j)});
      m.normals.insert(m.normals.end(), {0.f, 1.f, 0.f});
      m.colors.insert(m.colors.end(), {100, 100, 100, 255});
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      m.indices.insert(m.indices.end(), {a, c, b, b, c, d});
    }
  for (int k = 0; k < 10; ++k) {
    const float x0 = 2.f + 3.5f * k, z0 = 5.f, h = 4.f + k;
    const float corners[4][2] = {{x0, z0}, {x0 + 2, z0}, {x0 + 2, z0 + 2}, {x0, z0 + 2}};
    for (int w = 0; w < 4; ++w) {  // walls
      const float* p = corners[w];
      const float* q = corners[(w + 1) % 4];
      const auto base = static_cast<uint32_t>(m.vertexCount());
      const float nx = q[1] - p[1], nz = -(q[0] - p[0]);
      for (const float* c : {p, q})
        for (float y : {0.f, h}) {
          m.positions.insert(m.positions.end(), {c[0], y, c[1]});
          m.normals.insert(m.normals.end(), {nx / 2, 0.f, nz / 2});
          m.colors.insert(m.colors.end(), {200, 180, 160, 255});
        }
      m.indices.insert(m.indices.end(), {base, base + 2, base + 1, base + 1, base + 2, base + 3});
    }
    const auto base = static_cast<uint32_t>(m.vertexCount());  // roof
    for (const auto& c : corners) {
      m.positions.insert(m.positions.end(), {c[0], h, c[1]});
      m.normals.insert(m.normals.end(), {0.f, 1.f, 0.f});
      m.colors.insert(m.colors.end(), {150, 60, 50, 255});
    }
    m.indices.insert(m.indices.end(), {base, base + 3, base + 2, base, base + 2, base + 1});
  }
  return m;
}

TEST(LodChain, LevelsLoseTrianglesAndErrorsGrow) {
  const geo::MeshData full = blockLike();
  const std::vector<LodLevel> levels = buildLodChain(full, {});
  ASSERT_GE(levels.size(), 3u);
  ASSERT_LE(levels.size(), 4u);
  EXPECT_EQ(levels[0].error_m, 0.0);
  EXPECT_EQ(levels[0].mesh.indices, full.indices);
  for (size_t k = 1; k < levels.size(); ++k) {
    const auto& l = levels[k];
    EXPECT_LE(double(l.mesh.triangleCount()), 0.9 * double(levels[k - 1].mesh.triangleCount())) << "level " << k;
    EXPECT_GT(l.mesh.triangleCount(), 0u);
    EXPECT_TRUE(std::isfinite(l.error_m));
    EXPECT_GE(l.error_m, levels[k - 1].error_m) << "level " << k;
    // Compact: every vertex is used, attributes follow the vertices.
    std::vector<bool> used(l.mesh.vertexCount(), false);
    for (uint32_t i : l.mesh.indices) used.at(i) = true;
    EXPECT_EQ(std::count(used.begin(), used.end(), false), 0);
    EXPECT_EQ(l.mesh.normals.size(), l.mesh.positions.size());
    EXPECT_EQ(l.mesh.colors.size(), l.mesh.vertexCount() * 4);
  }
  // Level 1 aims at half the triangles and gets close without going sloppy.
  EXPECT_LE(levels[1].mesh.triangleCount(), full.triangleCount() / 2 + full.triangleCount() / 20 + 1);
  // Deterministic.
  const std::vector<LodLevel> again = buildLodChain(full, {});
  ASSERT_EQ(again.size(), levels.size());
  for (size_t k = 0; k < levels.size(); ++k) EXPECT_EQ(again[k].mesh.indices, levels[k].mesh.indices);
}

TEST(LodChain, NoneAndTinyMeshesKeepOneLevel) {
  LodOptions none;
  none.enabled = false;
  EXPECT_EQ(buildLodChain(blockLike(), none).size(), 1u);
  geo::MeshData tri;
  tri.positions = {0, 0, 0, 1, 0, 0, 0, 0, 1};
  tri.indices = {0, 2, 1};
  EXPECT_EQ(buildLodChain(tri, {}).size(), 1u);
  EXPECT_EQ(buildLodChain(geo::MeshData{}, {}).size(), 1u);
}

TEST(LodChain, BadRatiosAreRefused) {
  for (std::vector<double> r : {std::vector<double>{0.5, 0.5}, {1.0}, {0.0}, {0.5, 0.25, 0.1, 0.05}, {0.2, 0.4}}) {
    LodOptions o;
    o.ratios = r;
    EXPECT_THROW(checkLodOptions(o), core::Error);
  }
  LodOptions ok;
  ok.ratios = {0.3};
  EXPECT_NO_THROW(checkLodOptions(ok));
  EXPECT_EQ(buildLodChain(blockLike(), ok).size(), 2u);
}

TEST(LodChain, BlockRecordCountsAreWhatDecodingGives) {
  for (package::GlbCodec codec : {package::GlbCodec::Draco, package::GlbCodec::Plain, package::GlbCodec::Meshopt}) {
    package::GlbOptions glb;
    glb.codec = codec;
    const char* draco = package::glbCodecName(codec);
    graph::BlockRecord rec;
    LodStats stats;
    const std::vector<uint8_t> bytes = encodeBlock(blockLike(), {}, glb, rec, stats);
    ASSERT_GE(rec.lod_count, 3u);
    EXPECT_EQ(rec.triangle_count, rec.triangles[0]);
    EXPECT_EQ(rec.vertex_count, rec.vertices[0]);
    for (uint32_t k = 0; k < rec.lod_count; ++k) {
      geo::MeshData out;
      std::string err;
      ASSERT_EQ(package::decodeGlbLevel(bytes.data(), bytes.size(), k, out, err), core::Status::Ok) << err;
      EXPECT_EQ(out.triangleCount(), rec.triangles[k]) << "level " << k << " codec " << draco;
      EXPECT_EQ(out.vertexCount(), rec.vertices[k]) << "level " << k << " codec " << draco;
      if (k > 0) {
        EXPECT_LT(rec.triangles[k], rec.triangles[k - 1]);
        EXPECT_GE(rec.error_m[k], rec.error_m[k - 1]);
      }
    }
    for (uint32_t k = rec.lod_count; k < graph::kMaxBlockLods; ++k) EXPECT_EQ(rec.triangles[k], 0u);
    // The record passes the parser's rules once the bake gives it its blob.
    graph::BlockRecord stored = rec;
    stored.blob = 0;
    EXPECT_NO_THROW(graph::serializeBlocks({stored}));
    EXPECT_EQ(stats.blocks[0], 1u);
    EXPECT_EQ(stats.triangles[0], rec.triangles[0]);
    EXPECT_LE(rec.bbox_min[1], -0.2f);
    EXPECT_FLOAT_EQ(rec.bbox_max[1], 13.f);
  }
}

}  // namespace
}  // namespace blvd::bake
