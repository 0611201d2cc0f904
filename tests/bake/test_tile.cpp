// `blvd bake --tile 2x2` (sdk/bake/tile): Monaco baked once plain and once as
// 2 x 2 copies. The tiled package has exactly 4x the blocks, cells,
// junctions and buildings, its graph keeps the invariants, copy k is copy 0
// shifted (ids offset per copy, geometry and impostors the same), and the
// pool sizing a runtime plans from is the same for both packages.
#include <gtest/gtest.h>

#include <filesystem>

#include "bake/bake.h"
#include "stream/city.h"

namespace blvd::bake {
namespace {

const std::string kOsm = std::string(BLVD_DATA_DIR) + "/osm/monaco-geofabrik-2026.osm.pbf";

class Tile : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(std::string(BLVD_BINARY_DIR) + "/test-tile");
    std::filesystem::create_directories(*dir_);
    for (uint32_t n : {1u, 2u}) {
      BakeOptions opt;
      opt.quiet = true;
      // Single impostors on two cells: enough to see them copied, cheap to capture.
      opt.impostor.mode = ImpostorMode::Single;
      opt.select_cells = [](const graph::StreetGraph&) { return std::vector<uint32_t>{10, 11}; };
      opt.tile.nx = opt.tile.ny = n;
      const std::string path = *dir_ + "/monaco" + std::to_string(n) + ".blvd";
      bakeCity(kOsm, path, opt);
      auto* city = new stream::City;
      std::string err;
      ASSERT_EQ(city->open(path, err), core::Status::Ok) << err;
      (n == 1 ? one_ : four_) = city;
    }
  }
  static void TearDownTestSuite() {
    delete one_;
    delete four_;
    delete dir_;
  }
  static std::string* dir_;
  static stream::City *one_, *four_;
};
std::string* Tile::dir_ = nullptr;
stream::City* Tile::one_ = nullptr;
stream::City* Tile::four_ = nullptr;

TEST_F(Tile, FourTimesTheCityAndTheGraphInvariantsHold) {
  const auto &h1 = one_->header(), &h4 = four_->header();
  EXPECT_EQ(h4.block_count, 4 * h1.block_count);
  EXPECT_EQ(h4.cell_count, 4 * h1.cell_count);
  EXPECT_EQ(h4.junction_count, 4 * h1.junction_count);
  EXPECT_EQ(h4.building_count, 4 * h1.building_count);
  EXPECT_EQ(h4.triangle_count, 4 * h1.triangle_count);
  EXPECT_EQ(four_->package().blobCount(), 4 * one_->package().blobCount());
  const graph::StreetGraph &g1 = one_->graph(), &g4 = four_->graph();
  const auto bad = graph::checkInvariants(g4);
  EXPECT_TRUE(bad.empty()) << bad.front();
  EXPECT_EQ(g4.componentCount(), 4 * g1.componentCount());  // copies are disconnected
  size_t unbounded = 0;
  for (const auto& f : g4.faces) unbounded += f.unbounded;
  EXPECT_EQ(unbounded, 4u);  // each copy keeps its own outside
  EXPECT_GT(h4.bounds_max[0] - h4.bounds_min[0], 2 * (h1.bounds_max[0] - h1.bounds_min[0]));
}

TEST_F(Tile, EachCopyIsCopyZeroShifted) {
  const graph::StreetGraph &g1 = one_->graph(), &g4 = four_->graph();
  const uint32_t V = uint32_t(g1.vertices.size()), H = uint32_t(g1.halfedges.size()), F = uint32_t(g1.faces.size());
  const uint32_t B = one_->package().blobCount();
  for (uint32_t k = 0; k < 4; ++k) {
    const glm::dvec2 off = g4.vertices[k * V].p - g1.vertices[0].p;
    if (k > 0) {
      EXPECT_GT(std::abs(off.x) + std::abs(off.y), 1000.0);
    }
    for (uint32_t v = 0; v < V; ++v) {
      ASSERT_NEAR(g4.vertices[k * V + v].p.x, g1.vertices[v].p.x + off.x, 1e-6);
      ASSERT_NEAR(g4.vertices[k * V + v].p.y, g1.vertices[v].p.y + off.y, 1e-6);
    }
    for (uint32_t h = 0; h < H; ++h) {
      ASSERT_EQ(g4.halfedges[k * H + h].twin, g1.halfedges[h].twin + k * H);
      ASSERT_EQ(g4.halfedges[k * H + h].face, g1.halfedges[h].face + k * F);
      ASSERT_EQ(g4.successors.count(k * H + h), g1.successors.count(h));
    }
    for (uint32_t b = 0; b < F; ++b) {
      const graph::BlockRecord &r1 = one_->blocks()[b], &r4 = four_->blocks()[k * F + b];
      ASSERT_EQ(r4.lod_count, r1.lod_count);
      ASSERT_EQ(r4.building_count, r1.building_count);
      for (uint32_t l = 0; l < graph::kMaxBlockLods; ++l) {
        ASSERT_EQ(r4.triangles[l], r1.triangles[l]);
        ASSERT_EQ(r4.vertices[l], r1.vertices[l]);
        ASSERT_EQ(r4.error_m[l], r1.error_m[l]);
      }
      if (r1.lod_count) {
        ASSERT_EQ(r4.blob, r1.blob + k * B);
      }
    }
    // One block's every level decodes to copy 0's geometry, shifted.
    uint32_t b = 0;
    while (one_->blocks()[b].lod_count < 3) ++b;
    for (uint32_t l = 0; l < one_->blocks()[b].lod_count; ++l) {
      geo::MeshData m1, m4;
      std::string err;
      ASSERT_EQ(one_->decodeBlock(b, l, m1, err), core::Status::Ok) << err;
      ASSERT_EQ(four_->decodeBlock(k * F + b, l, m4, err), core::Status::Ok) << err;
      ASSERT_EQ(m1.indices, m4.indices);
      for (size_t i = 0; i < m1.positions.size(); i += 3) {
        ASSERT_NEAR(m4.positions[i], m1.positions[i] + off.x, 2e-3);
        ASSERT_NEAR(m4.positions[i + 2], m1.positions[i + 2] - off.y, 2e-3);
      }
    }
    // The impostors baked for cells 10 and 11 are in every copy.
    for (uint32_t c : {10u, 11u}) {
      const auto &i1 = one_->cellTables().impostors[c], &i4 = four_->cellTables().impostors[k * H + c];
      ASSERT_EQ(i4.single.size(), i1.single.size());
      for (size_t l = 0; l < i1.single.size(); ++l) {
        EXPECT_EQ(i4.single[l].blob, i1.single[l].blob + k * B);
        EXPECT_EQ(i4.single[l].vertices, i1.single[l].vertices);
        geo::MeshData m;
        std::string err;
        EXPECT_EQ(four_->decodeImpostor(i4.single[l], m, err), core::Status::Ok) << err;
      }
    }
  }
  EXPECT_FALSE(one_->cellTables().impostors[10].single.empty());
}

TEST_F(Tile, PoolSizingIsTheSameAsForOneCopy) {
  const auto &a = one_->header(), &b = four_->header();
  const auto pa = package::poolSizing(a), pb = package::poolSizing(b);
  for (size_t i = 0; i < pa.size(); ++i) {
    if (std::string(pa[i].name).find("blob_bytes") == std::string::npos) {
      EXPECT_EQ(pa[i].value, pb[i].value) << pa[i].name;
    }
  }
  // The copies' GLBs carry a node translation per level: a few bytes of JSON more.
  const uint32_t slack = 48 * graph::kMaxBlockLods;
  EXPECT_GE(b.max_block_blob_bytes, a.max_block_blob_bytes);
  EXPECT_LE(b.max_block_blob_bytes, a.max_block_blob_bytes + slack);
  EXPECT_LE(b.max_cell_local_blob_bytes, a.max_cell_local_blob_bytes + slack * a.max_cell_local_blocks);
  EXPECT_LE(b.max_cell_blob_bytes, a.max_cell_blob_bytes + 48);
}

}  // namespace
}  // namespace blvd::bake
