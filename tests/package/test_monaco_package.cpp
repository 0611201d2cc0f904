// The baked Monaco package (fixture bake.monaco_geofabrik), checked by brute
// force against what decoding it gives: every block level decodes to exactly
// the counts its BLCK record promises, levels lose triangles, errors grow;
// the header's pool sizing fields equal a scan that decodes everything.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <webp/decode.h>

#include "common/monaco_city.h"
#include "render/slab_atlas.h"

namespace blvd {
namespace {

const stream::City& city() { return test::monacoCity(); }

TEST(MonacoPackage, EveryBlockLevelDecodesToItsRecordedCounts) {
  const auto& blocks = city().blocks();
  size_t multi = 0;
  for (uint32_t b = 0; b < blocks.size(); ++b) {
    const graph::BlockRecord& r = blocks[b];
    ASSERT_LE(r.lod_count, graph::kMaxBlockLods);
    multi += r.lod_count > 1;
    for (uint32_t k = 0; k < r.lod_count; ++k) {
      geo::MeshData m;
      std::string err;
      ASSERT_EQ(city().decodeBlock(b, k, m, err), core::Status::Ok) << err;
      ASSERT_EQ(m.vertexCount(), r.vertices[k]) << "block " << b << " level " << k;
      ASSERT_EQ(m.triangleCount(), r.triangles[k]) << "block " << b << " level " << k;
      ASSERT_TRUE(std::isfinite(r.error_m[k]));
      if (k > 0) {
        ASSERT_LT(r.triangles[k], r.triangles[k - 1]) << "block " << b;
        ASSERT_GE(r.error_m[k], r.error_m[k - 1]) << "block " << b;
      }
    }
    geo::MeshData m;
    std::string err;
    EXPECT_EQ(city().decodeBlock(b, r.lod_count, m, err), core::Status::NotFound);
    // Opened once, as the loader decodes: every level the same as decodeBlock's.
    if (r.lod_count == 0 || b % 7) continue;
    stream::City::BlockBlob blob;
    ASSERT_EQ(city().openBlock(b, blob, err), core::Status::Ok) << err;
    EXPECT_EQ(blob.block(), b);
    for (uint32_t k = r.lod_count; k-- > 0;) {
      geo::MeshData once, each;
      ASSERT_EQ(city().decodeBlockLevel(blob, k, once, err), core::Status::Ok) << err;
      ASSERT_EQ(city().decodeBlock(b, k, each, err), core::Status::Ok) << err;
      ASSERT_EQ(once.positions, each.positions) << "block " << b << " level " << k;
      ASSERT_EQ(once.indices, each.indices) << "block " << b << " level " << k;
    }
    EXPECT_EQ(city().decodeBlockLevel(blob, r.lod_count, m, err), core::Status::NotFound);
    blob.close();
    EXPECT_EQ(city().decodeBlockLevel(blob, 0, m, err), core::Status::Misuse);
  }
  stream::City::BlockBlob none;
  std::string err;
  EXPECT_EQ(city().openBlock(uint32_t(blocks.size()), none, err), core::Status::NotFound);
  EXPECT_NE(err.find("does not exist"), std::string::npos) << err;
  // The default bake makes a chain for nearly every block.
  EXPECT_GT(multi, blocks.size() * 9 / 10);
}

// Width and height from a JPEG's SOF marker or a PNG's IHDR.
bool imageSize(const std::vector<uint8_t>& img, uint32_t& w, uint32_t& h) {
  int ww = 0, hh = 0;
  if (img.size() > 12 && std::memcmp(img.data(), "RIFF", 4) == 0 && WebPGetInfo(img.data(), img.size(), &ww, &hh)) {
    w = uint32_t(ww), h = uint32_t(hh);
    return true;
  }
  if (img.size() > 24 && img[0] == 0x89 && img[1] == 'P') {
    w = uint32_t(img[16]) << 24 | uint32_t(img[17]) << 16 | uint32_t(img[18]) << 8 | img[19];
    h = uint32_t(img[20]) << 24 | uint32_t(img[21]) << 16 | uint32_t(img[22]) << 8 | img[23];
    return true;
  }
  for (size_t i = 2; i + 9 < img.size();) {
    if (img[i] != 0xFF) return false;
    const uint8_t marker = img[i + 1];
    const size_t len = size_t(img[i + 2]) << 8 | img[i + 3];
    if (marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC) {
      h = uint32_t(img[i + 5]) << 8 | img[i + 6];
      w = uint32_t(img[i + 7]) << 8 | img[i + 8];
      return true;
    }
    i += 2 + len;
  }
  return false;
}

TEST(MonacoPackage, HeaderPoolSizingEqualsABruteForceScan) {
  const auto& blocks = city().blocks();
  const auto& g = city().graph();
  const package::PackageReader& pkg = city().package();
  // Per block, from decoding every level.
  std::vector<uint64_t> v_all(blocks.size()), t_all(blocks.size()), v0(blocks.size()), t0(blocks.size()),
      bytes(blocks.size());
  package::PackageHeader e;  // expected
  for (uint32_t b = 0; b < blocks.size(); ++b) {
    for (uint32_t k = 0; k < blocks[b].lod_count; ++k) {
      geo::MeshData m;
      std::string err;
      ASSERT_EQ(city().decodeBlock(b, k, m, err), core::Status::Ok) << err;
      v_all[b] += m.vertexCount();
      t_all[b] += m.triangleCount();
      if (k == 0) v0[b] = m.vertexCount(), t0[b] = m.triangleCount();
    }
    bytes[b] = blocks[b].lod_count ? pkg.blobInfo(blocks[b].blob).size : 0;
    e.max_block_blob_bytes = std::max<uint32_t>(e.max_block_blob_bytes, uint32_t(bytes[b]));
    e.max_block_lod0_vertices = std::max<uint32_t>(e.max_block_lod0_vertices, uint32_t(v0[b]));
    e.max_block_lod0_triangles = std::max<uint32_t>(e.max_block_lod0_triangles, uint32_t(t0[b]));
    e.max_block_vertices = std::max<uint32_t>(e.max_block_vertices, uint32_t(v_all[b]));
    e.max_block_triangles = std::max<uint32_t>(e.max_block_triangles, uint32_t(t_all[b]));
  }
  for (uint32_t c = 0; c < g.cellCount(); ++c) {
    uint64_t n = 0, sv0 = 0, st0 = 0, sv = 0, st = 0, sb = 0;
    for (const uint32_t* b = g.local_blocks.begin(c); b != g.local_blocks.end(c); ++b)
      ++n, sv0 += v0[*b], st0 += t0[*b], sv += v_all[*b], st += t_all[*b], sb += bytes[*b];
    e.max_cell_local_blocks = std::max<uint32_t>(e.max_cell_local_blocks, uint32_t(n));
    e.max_cell_local_lod0_vertices = std::max<uint32_t>(e.max_cell_local_lod0_vertices, uint32_t(sv0));
    e.max_cell_local_lod0_triangles = std::max<uint32_t>(e.max_cell_local_lod0_triangles, uint32_t(st0));
    e.max_cell_local_vertices = std::max<uint32_t>(e.max_cell_local_vertices, uint32_t(sv));
    e.max_cell_local_triangles = std::max<uint32_t>(e.max_cell_local_triangles, uint32_t(st));
    e.max_cell_local_blob_bytes = std::max(e.max_cell_local_blob_bytes, sb);
  }
  ASSERT_TRUE(city().hasImpostors()) << "the fixture bakes impostors on a route";
  size_t layers_seen = 0;
  std::vector<std::vector<int>> cell_w, cell_h;  // each cell's decoded image sizes, layered then single
  for (const graph::CellImpostors& ci : city().cellTables().impostors) {
    uint64_t n = 0, sv = 0, st = 0, sb = 0, stex = 0;
    cell_w.emplace_back(), cell_h.emplace_back();
    for (const auto* list : {&ci.layered, &ci.single})
      for (const graph::ImpostorLayer& l : *list) {
        geo::MeshData m;
        std::string err;
        ASSERT_EQ(city().decodeImpostor(l, m, err), core::Status::Ok) << err;
        uint32_t w = 0, h = 0;
        ASSERT_TRUE(imageSize(m.image, w, h)) << "impostor blob " << l.blob << " has no readable image";
        EXPECT_EQ(w, l.texture_width);
        EXPECT_EQ(h, l.texture_height);
        EXPECT_EQ(m.vertexCount(), l.vertices);
        EXPECT_EQ(m.triangleCount(), l.triangles);
        const uint64_t blob = pkg.blobInfo(l.blob).size, tex = uint64_t{w} * h * 4;
        ++n, ++layers_seen, sv += m.vertexCount(), st += m.triangleCount(), sb += blob, stex += tex;
        cell_w.back().push_back(int(w)), cell_h.back().push_back(int(h));
        e.max_cell_blob_bytes = std::max<uint32_t>(e.max_cell_blob_bytes, uint32_t(blob));
        e.max_impostor_texture_bytes = std::max<uint32_t>(e.max_impostor_texture_bytes, uint32_t(tex));
        e.max_impostor_texture_width = std::max<uint16_t>(e.max_impostor_texture_width, uint16_t(w));
        e.max_impostor_texture_height = std::max<uint16_t>(e.max_impostor_texture_height, uint16_t(h));
      }
    e.max_cell_impostor_layers = std::max<uint32_t>(e.max_cell_impostor_layers, uint32_t(n));
    e.max_cell_impostor_vertices = std::max<uint32_t>(e.max_cell_impostor_vertices, uint32_t(sv));
    e.max_cell_impostor_triangles = std::max<uint32_t>(e.max_cell_impostor_triangles, uint32_t(st));
    e.max_cell_impostor_blob_bytes = std::max(e.max_cell_impostor_blob_bytes, sb);
    e.max_cell_impostor_texture_bytes = std::max(e.max_cell_impostor_texture_bytes, stex);
  }
  EXPECT_GT(layers_seen, 0u);
  // The slots' atlas: every cell's images packed as the loader packs them.
  e.impostor_atlas_width = uint16_t(render::atlasWidth(e.max_impostor_texture_width, e.max_cell_impostor_texture_bytes / 4));
  for (size_t c = 0; c < cell_w.size(); ++c) {
    const uint32_t n = uint32_t(cell_w[c].size());
    std::vector<int> x(n), y(n);
    std::vector<uint32_t> order(n);
    const int used = render::packSlabAtlas(cell_w[c].data(), cell_h[c].data(), n, e.impostor_atlas_width, x.data(),
                                           y.data(), order.data());
    ASSERT_GE(used, 0) << "cell " << c;
    e.impostor_atlas_height = std::max<uint16_t>(e.impostor_atlas_height, uint16_t(used));
    // And on an ETC2 atlas's grid, its width rounded up to it (5.1).
    const int etc2 = render::packSlabAtlas(cell_w[c].data(), cell_h[c].data(), n,
                                           render::atlasRound(e.impostor_atlas_width, render::kEtc2AtlasAlign),
                                           x.data(), y.data(), order.data(), render::kEtc2AtlasAlign);
    e.impostor_atlas_etc2_height = std::max<uint16_t>(e.impostor_atlas_etc2_height, uint16_t(etc2));
  }
  EXPECT_GT(e.impostor_atlas_height, 0u);
  EXPECT_GE(e.impostor_atlas_etc2_height, e.impostor_atlas_height);
  const package::PackageHeader& h = city().header();
  const auto got = package::poolSizing(h), want = package::poolSizing(e);
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < got.size(); ++i) EXPECT_EQ(got[i].value, want[i].value) << got[i].name;
  EXPECT_GT(h.max_cell_impostor_layers, 0u);
  EXPECT_GE(h.max_block_triangles, h.max_block_lod0_triangles);
}

// The runtime's nearest cell (for a pose the host sets) searches the segment
// grid in growing squares; a scan of every half-edge's every segment with the
// same cost (distance + 5 m × (1 − cos) of the heading difference) must give
// the same cell and arc length, near the streets, between them and far
// outside the city.
TEST(MonacoPackage, NearestCellEqualsAScanOfEverySegment) {
  const graph::StreetGraph& g = city().graph();
  glm::dvec2 lo(1e30), hi(-1e30);
  for (const glm::dvec2& q : g.points) lo = glm::min(lo, q), hi = glm::max(hi, q);
  uint64_t state = 12345;
  auto uniform = [&] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return double(state >> 11) / double(1ull << 53);
  };
  int far = 0;
  for (int k = 0; k < 600; ++k) {
    // Two in three inside the graph's box, the rest up to a box-size outside.
    const double m = k % 3 == 2 ? 1.0 : 0.0;
    const glm::dvec2 size = hi - lo;
    const glm::dvec2 p(lo.x - m * size.x + uniform() * (1 + 2 * m) * size.x,
                       lo.y - m * size.y + uniform() * (1 + 2 * m) * size.y);
    far += p.x < lo.x || p.y < lo.y || p.x > hi.x || p.y > hi.y;
    const double heading = uniform() * 360.0;
    const glm::dvec2 dir(std::sin(heading * M_PI / 180.0), std::cos(heading * M_PI / 180.0));
    double best = 1e300, best_arc = 0;
    uint32_t best_h = graph::kNone;
    std::vector<double> cell_cost(g.halfedges.size(), 1e300);  // each half-edge's lowest cost
    for (uint32_t h = 0; h < g.halfedges.size(); ++h) {
      const auto& e = g.halfedges[h];
      double along = 0;
      for (uint32_t i = 0; i + 1 < e.pts_count; ++i) {
        const glm::dvec2 a = g.points[e.pts_begin + i], d = g.points[e.pts_begin + i + 1] - a;
        const double len = glm::length(d);
        if (len < 1e-9) continue;
        const double t = std::clamp(glm::dot(p - a, d) / (len * len), 0.0, 1.0);
        const double cost = glm::length(a + d * t - p) + 5.0 * (1.0 - glm::dot(d / len, dir));
        cell_cost[h] = std::min(cell_cost[h], cost);
        if (cost < best) best = cost, best_h = h, best_arc = along + t * len;
        along += len;
      }
    }
    double arc = -1;
    const uint32_t got = city().nearestCell(p, heading, &arc);
    // Equal costs (a point level with two segments' ends) may pick either.
    if (got != best_h) {
      ASSERT_LT(got, g.halfedges.size()) << "point " << k;
      EXPECT_NEAR(cell_cost[got], best, 1e-9) << "point " << k << " (" << p.x << ", " << p.y << ")";
      continue;
    }
    EXPECT_NEAR(arc, best_arc, 1e-6) << "point " << k;
  }
  EXPECT_GT(far, 100);
}

}  // namespace
}  // namespace blvd
