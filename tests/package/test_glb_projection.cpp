// Texture coordinates projected from the positions (BLVD_projected_texcoords,
// package format 6.0): an impostor's depth mesh stores no uv, its decoder
// computes them from each capture's projection. Round trips with one capture
// and with several, the bytes it saves, and every malformed projection named.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>

#include "glb_test_util.h"
#include "package/glb.h"

namespace blvd::package {
namespace {

using core::Status;
using geo::MeshData;
using namespace glbtest;

// A camera looking down -z from `eye` (right +x, up +y) whose w x h image
// sits at (x0, y0) in an atlas of 256 x 128 texels: the projection the bake
// writes for a capture (impostor_bake.cpp, projectionOf), by hand.
struct Camera {
  float eye[3];
  double tan_half = 0.5;
  int x0, y0, w = 128, h = 128;

  TexcoordProjection::Shot shot() const {
    const double W = 256, H = 128;
    const double au = w / (2 * tan_half * W), cu = (x0 + 0.5 * w) / W;
    const double av = h / (2 * tan_half * H), cv = (y0 + 0.5 * h) / H;
    // Rows as (x, y, z) coefficients; forward is (0, 0, -1).
    const double rows[3][3] = {{au, 0, -cu}, {0, -av, -cv}, {0, 0, -1}};
    TexcoordProjection::Shot s;
    for (int k = 0; k < 3; ++k) {
      double t = 0;
      for (int c = 0; c < 3; ++c) {
        s.matrix[4 * k + c] = float(rows[k][c]);
        t -= rows[k][c] * eye[c];
      }
      s.matrix[4 * k + 3] = float(t);
    }
    const float rect[4] = {float(x0 / W), float(y0 / H), float((x0 + w) / W), float((y0 + h) / H)};
    std::memcpy(s.rect, rect, sizeof rect);
    return s;
  }
  // The image point (x, y) at depth z as a position, and its atlas uv.
  void point(double x, double y, double z, MeshData& m) const {
    const double sx = (2 * x / w - 1) * tan_half, sy = (1 - 2 * y / h) * tan_half;
    m.positions.insert(m.positions.end(), {float(eye[0] + sx * z), float(eye[1] + sy * z), float(eye[2] - z)});
    m.texcoords.insert(m.texcoords.end(), {float((x0 + x) / 256.0), float((y0 + y) / 128.0)});
  }
};

const Camera kLeft{{10, 2, -5}, 0.5, 0, 0};
const Camera kRight{{12, 2, -5}, 0.4, 128, 0};

// An n x n grid over each camera's image, each inner point moved by up to
// 0.4 of a cell (a depth mesh's vertices lie on contours, not on a grid),
// its depth a slanted facade.
MeshData depthMesh(const std::vector<Camera>& cams, int n, TexcoordProjection& proj) {
  MeshData m;
  for (size_t c = 0; c < cams.size(); ++c) {
    const auto base = static_cast<uint32_t>(m.vertexCount());
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        const bool inner = i > 0 && j > 0 && i < n && j < n;
        const double jx = inner ? 0.4 * std::sin(12.9898 * i + 78.233 * j) : 0.0;
        const double jy = inner ? 0.4 * std::cos(39.3468 * i + 11.135 * j) : 0.0;
        const double x = cams[c].w * (i + jx) / double(n), y = cams[c].h * (j + jy) / double(n);
        cams[c].point(x, y, 30.0 + 0.05 * x + 3.0 * std::sin(0.3 * j), m);
      }
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const uint32_t a = base + uint32_t(j * (n + 1) + i), b = a + 1, d = a + uint32_t(n + 1), e = d + 1;
        m.indices.insert(m.indices.end(), {a, d, b, b, d, e});
      }
    proj.shots.push_back(cams[c].shot());
    proj.vertex_shot.insert(proj.vertex_shot.end(), size_t(n + 1) * (n + 1), uint8_t(c));
  }
  m.image = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n', 1, 2, 3};
  m.image_mime = "image/png";
  return m;
}

GlbOptions projected(const TexcoordProjection& proj) {
  GlbOptions o;
  o.normal_bits = 0;
  o.position_bits = 15;
  o.projection = &proj;
  return o;
}

// Each decoded vertex's uv against the uv of the nearest source vertex.
void expectTexcoordsOf(const MeshData& src, const MeshData& out, float tol) {
  ASSERT_EQ(out.texcoords.size(), out.vertexCount() * 2);
  for (size_t v = 0; v < out.vertexCount(); ++v) {
    size_t best = 0;
    float bd = INFINITY;
    for (size_t s = 0; s < src.vertexCount(); ++s) {
      float d = 0;
      for (int k = 0; k < 3; ++k) d += std::fabs(src.positions[3 * s + k] - out.positions[3 * v + k]);
      if (d < bd) bd = d, best = s;
    }
    ASSERT_NEAR(out.texcoords[2 * v], src.texcoords[2 * best], tol) << "vertex " << v;
    ASSERT_NEAR(out.texcoords[2 * v + 1], src.texcoords[2 * best + 1], tol) << "vertex " << v;
  }
}

TEST(GlbProjection, TexcoordsComeBackFromThePositions) {
  for (const std::vector<Camera>& cams : {std::vector<Camera>{kLeft}, std::vector<Camera>{kLeft, kRight}}) {
    TexcoordProjection proj;
    const MeshData src = depthMesh(cams, 8, proj);
    const auto glb = encodeGlb(src, projected(proj));
    const auto doc = glbJson(glb);
    const auto& prim = doc["meshes"][0]["primitives"][0];
    EXPECT_FALSE(prim["attributes"].contains("TEXCOORD_0"));
    EXPECT_EQ(prim["attributes"].contains("_SHOT"), cams.size() > 1);
    EXPECT_EQ(prim["extensions"]["BLVD_projected_texcoords"]["count"], cams.size());
    EXPECT_NE(doc["extensionsRequired"].dump().find("BLVD_projected_texcoords"), std::string::npos);
    MeshData out;
    std::string err;
    ASSERT_EQ(decodeGlb(glb.data(), glb.size(), out, err), Status::Ok) << err;
    EXPECT_EQ(out.triangleCount(), src.triangleCount());
    EXPECT_EQ(out.image, src.image);
    // 15-bit positions over a box of about 40 m: millimetres, a few
    // thousandths of a texel at 30 m.
    expectTexcoordsOf(src, out, 1e-4f);
  }
}

// What the extension is for: the same mesh without its uv attribute.
TEST(GlbProjection, SmallerThanStoredTexcoords) {
  TexcoordProjection proj;
  const MeshData src = depthMesh({kLeft, kRight}, 40, proj);
  GlbOptions stored = projected(proj);
  stored.projection = nullptr;
  stored.texcoord_bits = 11;
  const size_t with_uv = encodeGlb(src, stored).size(), without = encodeGlb(src, projected(proj)).size();
  EXPECT_LT(without, with_uv * 9 / 10) << without << " against " << with_uv;
  // Other codecs keep TEXCOORD_0.
  GlbOptions meshopt = projected(proj);
  meshopt.codec = GlbCodec::Meshopt;
  EXPECT_TRUE(glbJson(encodeGlb(src, meshopt))["meshes"][0]["primitives"][0]["attributes"].contains("TEXCOORD_0"));
}

TEST(GlbProjection, EncoderRefusesAProjectionThatMovesTheTexture) {
  TexcoordProjection proj;
  MeshData src = depthMesh({kLeft, kRight}, 4, proj);
  auto refused = [&](const MeshData& m, const TexcoordProjection& p, const std::string& why) {
    try {
      encodeGlb(m, projected(p));
      ADD_FAILURE() << "accepted; expected: " << why;
    } catch (const core::Error& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
  };
  MeshData moved = src;
  moved.texcoords[6] += 0.01f;
  refused(moved, proj, "vertex 3 projects to");
  TexcoordProjection wrong = proj;
  wrong.vertex_shot[0] = 2;
  refused(src, wrong, "vertex 0 names shot 2");
  wrong = proj;
  wrong.vertex_shot.pop_back();
  refused(src, wrong, "49 vertex shots for 50 vertices");
  refused(src, TexcoordProjection{}, "0 shots");
  std::vector<MeshData> levels{src, src};
  EXPECT_THROW(encodeGlbLevels(levels, projected(proj)), core::Error);
}

// The GLB of a two-capture mesh with its JSON changed by `edit` and its BIN
// chunk by `bin_edit`.
template <typename Edit, typename BinEdit>
std::vector<uint8_t> tampered(Edit edit, BinEdit bin_edit) {
  TexcoordProjection proj;
  const auto glb = encodeGlb(depthMesh({kLeft, kRight}, 4, proj), projected(proj));
  nlohmann::json doc = glbJson(glb);
  uint32_t json_len = 0;
  std::memcpy(&json_len, glb.data() + 12, 4);
  std::vector<uint8_t> bin(glb.begin() + 20 + json_len + 8, glb.end());
  edit(doc);
  bin_edit(doc, bin);
  return makeGlb(doc.dump(), bin);
}

TEST(GlbProjection, DecoderNamesEveryMalformedProjection) {
  using nlohmann::json;
  auto ext = [](json& d) -> json& { return d["meshes"][0]["primitives"][0]["extensions"]["BLVD_projected_texcoords"]; };
  auto keep = [](json&, std::vector<uint8_t>&) {};
  struct Case {
    std::vector<uint8_t> glb;
    const char* expect;
  };
  const Case cases[] = {
      {tampered([&](json& d) { ext(d)["count"] = 0; }, keep), "0 shots (1 to 256)"},
      {tampered([&](json& d) { ext(d)["count"] = 3; }, keep), "bufferView holds 128 bytes, 3 shots take 192"},
      {tampered([&](json& d) { ext(d).erase("count"); }, keep), "count: required but missing"},
      {tampered([&](json& d) { d["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = 1; }, keep),
       "TEXCOORD_0 and BLVD_projected_texcoords both"},
      {tampered(
           [](json& d) {
             auto& prim = d["meshes"][0]["primitives"][0];
             prim["attributes"].erase("_SHOT");
             prim["extensions"]["KHR_draco_mesh_compression"]["attributes"].erase("_SHOT");
           },
           keep),
       "2 shots but no _SHOT attribute"},
      {tampered([&](json& d) { ext(d)["count"] = 1, d["bufferViews"][ext(d)["bufferView"].get<int>()]["byteLength"] = 64; },
                keep),
       "names shot 1 of 1"},  // a vertex of the second capture
      {tampered([](json&) {},
                [&](json& d, std::vector<uint8_t>& bin) {
                  // Row w of both captures zero: no vertex is in front.
                  const size_t at = d["bufferViews"][ext(d)["bufferView"].get<int>()].value("byteOffset", size_t{0});
                  for (size_t s = 0; s < 2; ++s) std::memset(bin.data() + at + s * 64 + 32, 0, 16);
                }),
       "is not in front of shot"},
  };
  for (const Case& c : cases) {
    MeshData out;
    std::string err;
    EXPECT_EQ(decodeGlb(c.glb.data(), c.glb.size(), out, err), Status::Corrupt) << c.expect;
    EXPECT_NE(err.find(c.expect), std::string::npos) << "expected \"" << c.expect << "\" in: " << err;
    EXPECT_NE(err.find("BLVD_projected_texcoords"), std::string::npos) << err;
    EXPECT_TRUE(out.empty());
  }
}

}  // namespace
}  // namespace blvd::package
