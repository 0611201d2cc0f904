// GLB levels of detail (MSFT_lod): each level decodes to exactly the counts
// the encoder reported, level 0 is what a plain decodeGlb() (or any viewer)
// sees, missing levels and malformed MSFT_lod are errors, and translateGlb()
// moves every level.
#include <gtest/gtest.h>

#include <cstring>
#include <nlohmann/json.hpp>

#include "core/status.h"
#include "package/glb.h"

namespace blvd::package {
namespace {

using core::Status;
using geo::MeshData;

// An n x n grid of quads (2 n^2 triangles) at height y, shared vertices,
// normals up, one colour; then a smaller one, and so on.
MeshData grid(int n, float y = 0) {
  MeshData m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      m.positions.insert(m.positions.end(), {float(i), y, float(j)});
      m.normals.insert(m.normals.end(), {0.f, 1.f, 0.f});
      m.colors.insert(m.colors.end(), {120, 130, 140, 255});
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      m.indices.insert(m.indices.end(), {a, c, b, b, c, d});
    }
  return m;
}

nlohmann::json jsonOf(const std::vector<uint8_t>& glb) {
  uint32_t len;
  std::memcpy(&len, glb.data() + 12, 4);
  return nlohmann::json::parse(glb.begin() + 20, glb.begin() + 20 + len);
}

class GlbLevels : public ::testing::TestWithParam<GlbCodec> {};

TEST_P(GlbLevels, EachLevelDecodesToItsRecordedCounts) {
  GlbOptions opt;
  opt.codec = GetParam();
  const std::vector<MeshData> levels = {grid(8), grid(4), grid(2)};
  std::vector<GlbMeshCounts> counts;
  const std::vector<uint8_t> glb = encodeGlbLevels(levels, opt, &counts);
  ASSERT_EQ(counts.size(), 3u);
  for (uint32_t k = 0; k < 3; ++k) {
    MeshData out;
    std::string err;
    ASSERT_EQ(decodeGlbLevel(glb.data(), glb.size(), k, out, err), Status::Ok) << err;
    EXPECT_EQ(out.triangleCount(), counts[k].triangles) << "level " << k;
    EXPECT_EQ(out.vertexCount(), counts[k].vertices) << "level " << k;
    EXPECT_EQ(out.triangleCount(), levels[k].triangleCount());
    EXPECT_EQ(out.vertexCount(), levels[k].vertexCount());
  }
  // Level 0 is what a reader without MSFT_lod gets.
  MeshData plain, l0;
  std::string err;
  ASSERT_EQ(decodeGlb(glb.data(), glb.size(), plain, err), Status::Ok) << err;
  ASSERT_EQ(decodeGlbLevel(glb.data(), glb.size(), 0, l0, err), Status::Ok) << err;
  EXPECT_EQ(plain.positions, l0.positions);
  EXPECT_EQ(plain.indices, l0.indices);
  // Past the last level.
  MeshData none;
  EXPECT_EQ(decodeGlbLevel(glb.data(), glb.size(), 3, none, err), Status::NotFound);
  EXPECT_NE(err.find("2 lower levels, level 3 requested"), std::string::npos) << err;
  EXPECT_TRUE(none.empty());
  const nlohmann::json j = jsonOf(glb);
  EXPECT_EQ(j["scenes"][0]["nodes"], nlohmann::json::array({0}));
  EXPECT_EQ(j["nodes"][0]["extensions"]["MSFT_lod"]["ids"], nlohmann::json::array({1, 2}));
  EXPECT_NE(j["extensionsUsed"].dump().find("MSFT_lod"), std::string::npos);
  EXPECT_EQ(j.value("extensionsRequired", nlohmann::json::array()).dump().find("MSFT_lod"), std::string::npos);
}

// GlbDocument: parsed once, each level decodes to what decodeGlbLevel gives.
TEST_P(GlbLevels, ADocumentParsedOnceDecodesEveryLevel) {
  GlbOptions opt;
  opt.codec = GetParam();
  const std::vector<uint8_t> glb = encodeGlbLevels({grid(8), grid(4), grid(2)}, opt);
  GlbDocument doc;
  std::string err;
  EXPECT_FALSE(doc.isOpen());
  MeshData out;
  EXPECT_EQ(doc.decodeLevel(0, out, err), Status::Corrupt);
  EXPECT_NE(err.find("not open"), std::string::npos) << err;
  ASSERT_EQ(doc.open(glb.data(), glb.size(), err), Status::Ok) << err;
  for (uint32_t k : {2u, 0u, 1u, 1u}) {  // any order, any number of times
    MeshData once, each;
    ASSERT_EQ(doc.decodeLevel(k, once, err), Status::Ok) << err;
    ASSERT_EQ(decodeGlbLevel(glb.data(), glb.size(), k, each, err), Status::Ok) << err;
    EXPECT_EQ(once.positions, each.positions) << "level " << k;
    EXPECT_EQ(once.indices, each.indices) << "level " << k;
    EXPECT_EQ(once.colors, each.colors) << "level " << k;
  }
  EXPECT_EQ(doc.decodeLevel(3, out, err), Status::NotFound);
  EXPECT_TRUE(out.empty());
  // A failed open leaves the document closed; the errors are decodeGlb's.
  std::vector<uint8_t> cut(glb.begin(), glb.begin() + 30);
  EXPECT_EQ(doc.open(cut.data(), cut.size(), err), Status::Corrupt);
  EXPECT_FALSE(doc.isOpen());
  MeshData direct;
  std::string direct_err;
  EXPECT_EQ(decodeGlb(cut.data(), cut.size(), direct, direct_err), Status::Corrupt);
  EXPECT_EQ(err, direct_err);
}

INSTANTIATE_TEST_SUITE_P(Codecs, GlbLevels, ::testing::Values(GlbCodec::Plain, GlbCodec::Draco, GlbCodec::Meshopt),
                         [](const ::testing::TestParamInfo<GlbCodec>& i) { return std::string(glbCodecName(i.param)); });

TEST(GlbLevelsCounts, MeshWithoutNormalsCountsUnweldedVertices) {
  MeshData m = grid(3);
  m.normals.clear();
  GlbMeshCounts c;
  const std::vector<uint8_t> glb = encodeGlb(m, {}, &c);
  MeshData out;
  std::string err;
  ASSERT_EQ(decodeGlb(glb.data(), glb.size(), out, err), Status::Ok) << err;
  EXPECT_EQ(c.vertices, 3 * c.triangles);
  EXPECT_EQ(out.vertexCount(), c.vertices);
  EXPECT_EQ(out.triangleCount(), c.triangles);
}

TEST(GlbLevelsCounts, SingleMeshHasNoLevels) {
  const std::vector<uint8_t> glb = encodeGlb(grid(2));
  MeshData out;
  std::string err;
  EXPECT_EQ(decodeGlbLevel(glb.data(), glb.size(), 1, out, err), Status::NotFound);
  EXPECT_NE(err.find("no MSFT_lod"), std::string::npos) << err;
  EXPECT_EQ(jsonOf(glb).count("extensionsUsed") ? jsonOf(glb)["extensionsUsed"].dump().find("MSFT_lod")
                                                : std::string::npos,
            std::string::npos);
}

TEST(GlbLevelsCounts, LevelsMustMatchLevelZero) {
  MeshData no_colour = grid(2);
  no_colour.colors.clear();
  EXPECT_THROW(encodeGlbLevels({grid(4), no_colour}), core::Error);
  EXPECT_THROW(encodeGlbLevels({grid(4), MeshData{}}), core::Error);
  EXPECT_THROW(encodeGlbLevels({}), core::Error);
  try {
    MeshData bad = grid(2);
    bad.indices[0] = 999;
    encodeGlbLevels({grid(4), bad});
    FAIL();
  } catch (const core::Error& e) {
    EXPECT_NE(std::string(e.what()).find("level 1"), std::string::npos) << e.what();
  }
}

TEST(GlbLevelsCounts, MalformedLodIsCorruptAndTruncationsFail) {
  std::vector<uint8_t> glb = encodeGlbLevels({grid(4), grid(2)});
  // Point MSFT_lod at a node that does not exist: same JSON length ("1" -> "7").
  const std::string key = "\"ids\":[1]";
  uint32_t len;
  std::memcpy(&len, glb.data() + 12, 4);
  std::string js(glb.begin() + 20, glb.begin() + 20 + len);
  const size_t at = js.find(key);
  ASSERT_NE(at, std::string::npos) << js;
  std::vector<uint8_t> bad = glb;
  bad[20 + at + key.size() - 2] = '7';
  MeshData out;
  std::string err;
  EXPECT_EQ(decodeGlbLevel(bad.data(), bad.size(), 1, out, err), Status::Corrupt);
  EXPECT_NE(err.find("MSFT_lod.ids"), std::string::npos) << err;
  for (size_t n = 0; n < glb.size(); n += 7)
    EXPECT_NE(decodeGlbLevel(glb.data(), n, 1, out, err), Status::Ok) << "length " << n;
}

TEST(GlbLevelsCounts, TranslateMovesEveryLevel) {
  const std::vector<uint8_t> glb = encodeGlbLevels({grid(4), grid(2)});
  const float off[3] = {1000.f, 0.f, -250.f};
  const std::vector<uint8_t> moved = translateGlb(glb.data(), glb.size(), off);
  for (uint32_t k = 0; k < 2; ++k) {
    MeshData a, b;
    std::string err;
    ASSERT_EQ(decodeGlbLevel(glb.data(), glb.size(), k, a, err), Status::Ok) << err;
    ASSERT_EQ(decodeGlbLevel(moved.data(), moved.size(), k, b, err), Status::Ok) << err;
    ASSERT_EQ(a.positions.size(), b.positions.size());
    ASSERT_EQ(a.indices, b.indices);
    for (size_t i = 0; i < a.positions.size(); ++i) EXPECT_NEAR(b.positions[i], a.positions[i] + off[i % 3], 1e-3);
  }
  const std::vector<uint8_t> garbage(40, 7);
  EXPECT_THROW(translateGlb(garbage.data(), garbage.size(), off), core::Error);
}

}  // namespace
}  // namespace blvd::package
