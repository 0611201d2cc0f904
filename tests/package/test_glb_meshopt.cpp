// EXT_meshopt_compression: the view codec against the extension's rules
// (every mode and filter, every constraint), our GLBs' layout (fallback
// buffer, KHR_mesh_quantization types), precision per option, and bad
// compressed views named in the error.
#include <gtest/gtest.h>
#include <meshoptimizer.h>

#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>
#include <random>

#include "glb_test_util.h"
#include "package/glb.h"
#include "package/meshopt_view.h"

namespace blvd::package {
namespace {

using core::Status;
using geo::MeshData;
using namespace glbtest;

GlbOptions meshopt() {
  GlbOptions o;
  o.codec = GlbCodec::Meshopt;
  return o;
}

std::vector<uint8_t> decodeView(const std::vector<uint8_t>& c, MeshoptMode mode, MeshoptFilter f, size_t count,
                                size_t stride, Status want = Status::Ok, std::string* err_out = nullptr) {
  std::vector<uint8_t> out;
  std::string err;
  EXPECT_EQ(decodeMeshoptView(c.data(), c.size(), {mode, f, count, stride}, out, err), want) << err;
  if (err_out) *err_out = err;
  return out;
}

// ------------------------------------------------------- the view codec --

TEST(MeshoptView, AttributesRoundTripBitExact) {
  std::mt19937 rng(7);
  for (size_t stride : {4u, 8u, 12u, 16u, 256u})
    for (size_t count : {0u, 1u, 3u, 17u, 1000u}) {
      std::vector<uint8_t> raw(count * stride);
      for (auto& b : raw) b = static_cast<uint8_t>(rng() % 7);  // small deltas, as real data
      const auto c = encodeMeshoptAttributes(raw.data(), count, stride);
      EXPECT_EQ(decodeView(c, MeshoptMode::Attributes, MeshoptFilter::None, count, stride), raw)
          << "stride " << stride << " count " << count;
    }
  EXPECT_THROW(encodeMeshoptAttributes(nullptr, 0, 6), core::Error);
  EXPECT_THROW(encodeMeshoptAttributes(nullptr, 0, 260), core::Error);
}

TEST(MeshoptView, TrianglesAndIndicesDecodeTo16Or32Bits) {
  const std::vector<uint32_t> tri = {0, 1, 2, 2, 1, 3, 3, 1, 4, 70000 % 5, 4, 2};
  const auto c = encodeMeshoptTriangles(tri.data(), tri.size(), 5);
  for (size_t isize : {2u, 4u}) {
    const auto out = decodeView(c, MeshoptMode::Triangles, MeshoptFilter::None, tri.size(), isize);
    ASSERT_EQ(out.size(), tri.size() * isize);
    for (size_t t = 0; t < tri.size(); t += 3) {  // same triangles, corners maybe rotated
      uint32_t v[3] = {0, 0, 0};
      for (int k = 0; k < 3; ++k) std::memcpy(&v[k], &out[(t + k) * isize], isize);
      bool same = false;
      for (int r = 0; r < 3; ++r)
        same |= v[r] == tri[t] && v[(r + 1) % 3] == tri[t + 1] && v[(r + 2) % 3] == tri[t + 2];
      EXPECT_TRUE(same) << "triangle " << t / 3;
    }
  }
  // INDICES (mode 2) keeps the sequence exactly.
  const std::vector<uint32_t> seq = {5, 9, 9, 0, 70000, 3};
  std::vector<uint8_t> sc(meshopt_encodeIndexSequenceBound(seq.size(), 70001));
  sc.resize(meshopt_encodeIndexSequence(sc.data(), sc.size(), seq.data(), seq.size()));
  const auto out = decodeView(sc, MeshoptMode::Indices, MeshoptFilter::None, seq.size(), 4);
  std::vector<uint32_t> back(seq.size());
  std::memcpy(back.data(), out.data(), out.size());
  EXPECT_EQ(back, seq);
  EXPECT_THROW(encodeMeshoptTriangles(tri.data(), 4, 5), core::Error);
}

TEST(MeshoptView, FiltersDecodeAsTheSpecSays) {
  // EXPONENTIAL: 2^e * m, one exponent per vector; 23 bits is exact for these.
  const std::vector<float> v = {1.5f, -2.25f, 1000.0f, 0.0f, 3.0f, -0.125f, 7.0f, 8.0f, 9.0f};
  std::vector<uint8_t> raw(v.size() * 4);
  meshopt_encodeFilterExp(raw.data(), 3, 12, 23, v.data());
  auto out = decodeView(encodeMeshoptAttributes(raw.data(), 3, 12), MeshoptMode::Attributes,
                        MeshoptFilter::Exponential, 3, 12);
  std::vector<float> f(9);
  std::memcpy(f.data(), out.data(), 36);
  EXPECT_EQ(f, v);
  // OCTAHEDRAL: unit vectors to snorm8 (stride 4) and snorm16 (stride 8).
  const std::vector<float> n = {0.6f, 0.0f, 0.8f, 0.0f, 0.0f, -1.0f, 0.0f, 0.0f, 0.267261f, 0.534522f, -0.801784f, 0.0f};
  for (size_t stride : {4u, 8u}) {
    const int bits = stride == 4 ? 8 : 16;
    std::vector<uint8_t> r(3 * stride);
    meshopt_encodeFilterOct(r.data(), 3, stride, bits, n.data());
    out = decodeView(encodeMeshoptAttributes(r.data(), 3, stride), MeshoptMode::Attributes,
                     MeshoptFilter::Octahedral, 3, stride);
    for (size_t e = 0; e < 3; ++e)
      for (int k = 0; k < 3; ++k) {
        const float q = stride == 4 ? static_cast<int8_t>(out[e * 4 + k]) / 127.0f
                                    : [&] { int16_t s; std::memcpy(&s, &out[e * 8 + k * 2], 2); return s / 32767.0f; }();
        EXPECT_NEAR(q, n[e * 4 + k], stride == 4 ? 0.02f : 2e-4f) << "stride " << stride << " vector " << e;
      }
  }
  // QUATERNION: unit quaternions in 8 bytes.
  const std::vector<float> q = {0.0f, 0.0f, 0.0f, 1.0f, 0.5f, 0.5f, 0.5f, 0.5f};
  std::vector<uint8_t> r(16);
  meshopt_encodeFilterQuat(r.data(), 2, 8, 12, q.data());
  out = decodeView(encodeMeshoptAttributes(r.data(), 2, 8), MeshoptMode::Attributes, MeshoptFilter::Quaternion, 2, 8);
  for (size_t i = 0; i < 8; ++i) {
    int16_t s;
    std::memcpy(&s, &out[i * 2], 2);
    EXPECT_NEAR(s / 32767.0f, q[i], 2e-3f) << i;
  }
}

TEST(MeshoptView, EveryConstraintOfTheExtensionIsChecked) {
  const std::vector<uint8_t> c = encodeMeshoptAttributes(std::vector<uint8_t>(48).data(), 4, 12);
  struct Case {
    MeshoptMode mode;
    MeshoptFilter filter;
    uint64_t count, stride;
    const char* expect;
  };
  const Case cases[] = {
      {MeshoptMode::Attributes, MeshoptFilter::None, 4, 6, "byteStride divisible by 4 and at most 256"},
      {MeshoptMode::Attributes, MeshoptFilter::None, 4, 260, "byteStride divisible by 4 and at most 256"},
      {MeshoptMode::Triangles, MeshoptFilter::None, 4, 4, "TRIANGLES needs a count divisible by 3"},
      {MeshoptMode::Triangles, MeshoptFilter::None, 3, 8, "byteStride of 2 or 4"},
      {MeshoptMode::Indices, MeshoptFilter::Exponential, 3, 4, "take no filter"},
      {MeshoptMode::Attributes, MeshoptFilter::Octahedral, 4, 12, "OCTAHEDRAL needs a byteStride of 4 or 8"},
      {MeshoptMode::Attributes, MeshoptFilter::Quaternion, 4, 4, "QUATERNION needs a byteStride of 8"},
      {MeshoptMode::Attributes, MeshoptFilter::None, 4, 0, "byteStride is 0"},
      {MeshoptMode::Attributes, MeshoptFilter::None, 1000000, 12, "expansion"},
      {MeshoptMode::Attributes, MeshoptFilter::None, uint64_t{1} << 62, 12, "expansion"},
  };
  for (const Case& k : cases) {
    std::string err;
    const auto out = decodeView(c, k.mode, k.filter, k.count, k.stride, Status::Corrupt, &err);
    EXPECT_NE(err.find(k.expect), std::string::npos) << "expected \"" << k.expect << "\" in: " << err;
    EXPECT_TRUE(out.empty());
  }
  // The codec's own refusals: a bad header byte, and every truncation.
  std::vector<uint8_t> bad = c;
  bad[0] = 0x00;
  std::string err;
  decodeView(bad, MeshoptMode::Attributes, MeshoptFilter::None, 4, 12, Status::Corrupt, &err);
  EXPECT_NE(err.find("bad header"), std::string::npos) << err;
  for (size_t n = 0; n < c.size(); ++n) {
    std::vector<uint8_t> cut(c.begin(), c.begin() + static_cast<ptrdiff_t>(n));
    std::vector<uint8_t> out;
    EXPECT_EQ(decodeMeshoptView(n ? cut.data() : nullptr, n, {MeshoptMode::Attributes, MeshoptFilter::None, 4, 12},
                                out, err),
              Status::Corrupt)
        << n;
  }
}

// ------------------------------------------------------------ our GLBs --

TEST(GlbMeshopt, RoundTripAndLayout) {
  const MeshData src = box();
  const std::vector<uint8_t> glb = encodeGlb(src, meshopt());
  const auto doc = glbJson(glb);
  EXPECT_EQ(doc["extensionsRequired"], nlohmann::json({"EXT_meshopt_compression", "KHR_mesh_quantization"}));
  EXPECT_EQ(doc["extensionsUsed"], nlohmann::json({"EXT_meshopt_compression", "KHR_mesh_quantization"}));
  // Buffer 0 is the BIN chunk with the compressed bytes; buffer 1 the
  // fallback (no data), big enough for every decoded view.
  ASSERT_EQ(doc["buffers"].size(), 2u);
  EXPECT_FALSE(doc["buffers"][1].contains("uri"));
  EXPECT_EQ(doc["buffers"][1]["extensions"]["EXT_meshopt_compression"]["fallback"], true);
  const size_t fallback = doc["buffers"][1]["byteLength"].get<size_t>();
  for (const auto& v : doc["bufferViews"]) {
    ASSERT_TRUE(v.contains("extensions")) << v.dump();
    const auto& e = v["extensions"]["EXT_meshopt_compression"];
    EXPECT_EQ(v["buffer"], 1);
    EXPECT_EQ(e["buffer"], 0);
    EXPECT_EQ(v["byteLength"].get<size_t>(), e["byteStride"].get<size_t>() * e["count"].get<size_t>());
    EXPECT_LE(v["byteOffset"].get<size_t>() + v["byteLength"].get<size_t>(), fallback);
    EXPECT_EQ(v["byteOffset"].get<size_t>() % 4, 0u);
    if (v.contains("byteStride")) {
      EXPECT_EQ(v["byteStride"], e["byteStride"]);
    }
    if (v["target"] == 34963) {  // index views: TRIANGLES, no byteStride on the parent (glTF 2.0)
      EXPECT_EQ(e["mode"], "TRIANGLES");
      EXPECT_FALSE(v.contains("byteStride"));
    } else {
      EXPECT_EQ(e["mode"], "ATTRIBUTES");
    }
  }
  const auto& attrs = doc["meshes"][0]["primitives"][0]["attributes"];
  const auto& nacc = doc["accessors"][attrs["NORMAL"].get<int>()];
  EXPECT_EQ(nacc["componentType"], 5122);  // 10 normal bits: snorm16
  EXPECT_EQ(nacc["normalized"], true);
  EXPECT_EQ(doc["bufferViews"][nacc["bufferView"].get<int>()]["extensions"]["EXT_meshopt_compression"]["filter"],
            "OCTAHEDRAL");
  const auto& pacc = doc["accessors"][attrs["POSITION"].get<int>()];
  EXPECT_EQ(pacc["componentType"], 5126);
  EXPECT_EQ(doc["bufferViews"][pacc["bufferView"].get<int>()]["extensions"]["EXT_meshopt_compression"]["filter"],
            "EXPONENTIAL");

  MeshData out;
  std::string err;
  ASSERT_EQ(decodeGlb(glb.data(), glb.size(), out, err), Status::Ok) << err;
  EXPECT_EQ(out.vertexCount(), src.vertexCount());
  EXPECT_EQ(out.triangleCount(), src.triangleCount());
  // 20 mantissa bits, one exponent per vertex: within 2^-19 of the vertex's
  // largest coordinate (1.5 m here).
  const float pos_tol = 1.5f * std::ldexp(1.0f, -19) * 1.01f;
  expectSameTriangles(src, out, pos_tol);
  expectSameAttributes(src, out, pos_tol, 0.01f);
  // The accessor's bounds are the decoded positions' own.
  for (size_t i = 0; i < out.positions.size(); ++i) {
    EXPECT_GE(out.positions[i], pacc["min"][i % 3].get<float>());
    EXPECT_LE(out.positions[i], pacc["max"][i % 3].get<float>());
  }
}

TEST(GlbMeshopt, PositionBitsSetThePrecisionAndTheSize) {
  // 2 km from the package origin, where block coordinates reach.
  const MeshData src = box(20.3f, 10.7f, 30.1f, 2000.37f, 5.13f, -1500.71f);
  size_t first_size = 0;
  float last_err = -1;
  for (int bits : {24, 20, 16, 12}) {
    GlbOptions opt = meshopt();
    opt.meshopt_position_bits = bits;
    const auto glb = encodeGlb(src, opt);
    MeshData out;
    std::string err;
    ASSERT_EQ(decodeGlb(glb.data(), glb.size(), out, err), Status::Ok) << err;
    const float tol = 2015.0f * std::ldexp(1.0f, -(bits - 1)) * 1.01f;
    expectSameTriangles(src, out, tol);
    float worst = 0;  // vertex order is the codec's: compare each vertex with its nearest source vertex
    for (size_t v = 0; v < out.vertexCount(); ++v) {
      float best = 1e30f;
      for (size_t u = 0; u < src.vertexCount(); ++u) {
        float d = 0;
        for (int k = 0; k < 3; ++k) d = std::max(d, std::fabs(out.positions[v * 3 + k] - src.positions[u * 3 + k]));
        best = std::min(best, d);
      }
      worst = std::max(worst, best);
    }
    EXPECT_LE(worst, tol) << bits << " bits";
    if (bits == 12) {
      EXPECT_GT(worst, 0.05f) << "12 bits at 2 km must be coarse: the filter is not applied";
    }
    EXPECT_GE(worst, last_err);
    if (bits == 24) first_size = glb.size();
    if (bits == 12) {
      EXPECT_LT(glb.size(), first_size) << "fewer bits, fewer bytes";
    }
    last_err = worst;
  }
  // 0: float32 as is, exact.
  GlbOptions exact = meshopt();
  exact.meshopt_position_bits = 0;
  const auto glb = encodeGlb(src, exact);
  MeshData out;
  std::string err;
  ASSERT_EQ(decodeGlb(glb.data(), glb.size(), out, err), Status::Ok) << err;
  expectSameTriangles(src, out, 0.0f);
  GlbOptions bad = meshopt();
  bad.meshopt_position_bits = 25;
  EXPECT_THROW(encodeGlb(src, bad), core::Error);
}

TEST(GlbMeshopt, NormalBitsChooseTheStorage) {
  const MeshData src = box();
  struct Want {
    int bits, component_type;
    float tol;
  };
  for (const Want& w : {Want{8, 5120, 0.02f}, Want{10, 5122, 0.004f}, Want{16, 5122, 1e-4f}, Want{0, 5126, 0.0f}}) {
    GlbOptions opt = meshopt();
    opt.normal_bits = w.bits;
    const auto glb = encodeGlb(src, opt);
    const auto doc = glbJson(glb);
    const auto& nacc = doc["accessors"][doc["meshes"][0]["primitives"][0]["attributes"]["NORMAL"].get<int>()];
    EXPECT_EQ(nacc["componentType"], w.component_type) << w.bits;
    MeshData out;
    std::string err;
    ASSERT_EQ(decodeGlb(glb.data(), glb.size(), out, err), Status::Ok) << err;
    expectSameAttributes(src, out, 1.5f * std::ldexp(1.0f, -19) * 1.01f, w.tol);
  }
}

TEST(GlbMeshopt, TexcoordsAreUnorm16InsideTheUnitSquareElseFloat) {
  MeshData src = box();
  for (size_t v = 0; v < src.vertexCount(); ++v)
    src.texcoords.insert(src.texcoords.end(), {(v % 4) * 0.25f + 0.01f, (v / 4) / 6.0f});
  for (bool inside : {true, false}) {
    if (!inside) src.texcoords[0] = 1.5f;
    const auto glb = encodeGlb(src, meshopt());
    const auto doc = glbJson(glb);
    const auto& tacc = doc["accessors"][doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"].get<int>()];
    EXPECT_EQ(tacc["componentType"], inside ? 5123 : 5126);
    MeshData out;
    std::string err;
    ASSERT_EQ(decodeGlb(glb.data(), glb.size(), out, err), Status::Ok) << err;
    ASSERT_EQ(out.texcoords.size(), out.vertexCount() * 2);
    // Each decoded vertex's uv is its source vertex's (matched by position).
    for (size_t v = 0; v < out.vertexCount(); ++v) {
      bool found = false;
      for (size_t u = 0; u < src.vertexCount() && !found; ++u) {
        bool same = true;
        for (int k = 0; k < 3 && same; ++k) same = std::fabs(out.positions[v * 3 + k] - src.positions[u * 3 + k]) < 1e-4f;
        for (int k = 0; k < 3 && same; ++k) same = std::fabs(out.normals[v * 3 + k] - src.normals[u * 3 + k]) < 1e-2f;
        if (!same) continue;
        found = true;
        for (int k = 0; k < 2; ++k)
          EXPECT_NEAR(out.texcoords[v * 2 + k], src.texcoords[u * 2 + k], inside ? 0.5f / 65535 : 0.0f);
      }
      EXPECT_TRUE(found) << v;
    }
  }
}

TEST(GlbMeshopt, UnusedVerticesAreDroppedAndCounted) {
  MeshData src = box();
  for (int k = 0; k < 3; ++k) src.positions.push_back(9.0f), src.normals.push_back(k == 1 ? 1.0f : 0.0f);
  src.colors.insert(src.colors.end(), {1, 2, 3, 255});
  GlbMeshCounts counts;
  const auto glb = encodeGlb(src, meshopt(), &counts);
  EXPECT_EQ(counts.vertices, 24u);
  EXPECT_EQ(counts.triangles, 12u);
  MeshData out;
  std::string err;
  ASSERT_EQ(decodeGlb(glb.data(), glb.size(), out, err), Status::Ok) << err;
  EXPECT_EQ(out.vertexCount(), counts.vertices);
}

// A hand-made meshopt GLB (one triangle) with one thing wrong per case.
TEST(GlbMeshopt, BadViewsAreNamed) {
  const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const uint32_t idx[3] = {0, 1, 2};
  const std::vector<uint8_t> pc = encodeMeshoptAttributes(pos, 3, 12);
  const std::vector<uint8_t> ic = encodeMeshoptTriangles(idx, 3, 3);
  std::vector<uint8_t> bin = pc;
  while (bin.size() % 4) bin.push_back(0);
  const size_t ioff = bin.size();
  bin.insert(bin.end(), ic.begin(), ic.end());
  while (bin.size() % 4) bin.push_back(0);
  auto doc = [&](const std::string& pos_view_ext, const std::string& pos_view = R"("byteLength":36,"byteStride":12)") {
    return R"({"asset":{"version":"2.0"},"extensionsRequired":["EXT_meshopt_compression"],
      "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],
      "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"},
                   {"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}],
      "buffers":[{"byteLength":)" + std::to_string(bin.size()) + R"(},{"byteLength":44,"extensions":{"EXT_meshopt_compression":{"fallback":true}}}],
      "bufferViews":[{"buffer":1,)" + pos_view + R"(,"extensions":{"EXT_meshopt_compression":{)" + pos_view_ext + R"(}}},
        {"buffer":1,"byteOffset":36,"byteLength":6,"extensions":{"EXT_meshopt_compression":
          {"buffer":0,"byteOffset":)" + std::to_string(ioff) + R"(,"byteLength":)" + std::to_string(ic.size()) +
           R"(,"byteStride":2,"count":3,"mode":"TRIANGLES"}}}]})";
  };
  const std::string good = R"("buffer":0,"byteLength":)" + std::to_string(pc.size()) +
                           R"(,"byteStride":12,"count":3,"mode":"ATTRIBUTES")";
  {
    MeshData out;
    std::string err;
    const auto glb = makeGlb(doc(good), bin);
    ASSERT_EQ(decodeGlb(glb.data(), glb.size(), out, err), Status::Ok) << err;
    EXPECT_EQ(out.positions, std::vector<float>(pos, pos + 9));
    EXPECT_EQ(out.indices.size(), 3u);
  }
  const std::string pl = std::to_string(pc.size());
  struct Case {
    std::string ext, view, expect;
  };
  const std::string view = R"("byteLength":36,"byteStride":12)";
  const Case cases[] = {
      {R"("buffer":0,"byteLength":)" + pl + R"(,"byteStride":12,"count":3,"mode":"SPARSE")", view,
       "bufferViews[0].extensions.EXT_meshopt_compression.mode: expected ATTRIBUTES, TRIANGLES or INDICES"},
      {good + R"(,"filter":"GZIP")", view, "EXT_meshopt_compression.filter: expected NONE"},
      {good, R"("byteLength":30,"byteStride":12)", "bufferViews[0].byteLength: 30 is not the extension's byteStride 12 x count 3"},
      {good, R"("byteLength":48,"byteStride":16)", "bufferViews[0].byteStride: 16 differs from the extension's 12"},
      {R"("buffer":0,"byteOffset":4000,"byteLength":)" + pl + R"(,"byteStride":12,"count":3,"mode":"ATTRIBUTES")", view,
       "EXT_meshopt_compression: byteOffset 4000 + byteLength " + pl + " runs past buffers[0]"},
      {R"("buffer":0,"byteLength":)" + pl + R"(,"byteStride":12,"mode":"ATTRIBUTES")", view,
       "EXT_meshopt_compression.count: required but missing"},
      {R"("buffer":0,"byteLength":)" + pl + R"(,"byteStride":12,"count":3,"mode":"ATTRIBUTES","filter":"OCTAHEDRAL")",
       view, "OCTAHEDRAL needs a byteStride of 4 or 8"},
      {R"("buffer":1,"byteLength":)" + pl + R"(,"byteStride":12,"count":3,"mode":"ATTRIBUTES")", view,
       "buffers[1]: no uri and no GLB BIN chunk"},
      {R"("buffer":0,"byteLength":)" + pl + R"(,"byteStride":12,"count":3000,"mode":"ATTRIBUTES")",
       R"("byteLength":36000,"byteStride":12)", "expansion"},
      {R"("buffer":0,"byteOffset":)" + std::to_string(ioff) + R"(,"byteLength":)" + std::to_string(ic.size()) +
           R"(,"byteStride":12,"count":3,"mode":"ATTRIBUTES")",
       view, "does not decode"},
  };
  for (const Case& c : cases) {
    const auto glb = makeGlb(doc(c.ext, c.view), bin);
    MeshData out;
    std::string err;
    EXPECT_EQ(decodeGlb(glb.data(), glb.size(), out, err), Status::Corrupt) << c.ext << " | " << c.view << "\n" << err;
    EXPECT_NE(err.find(c.expect), std::string::npos) << "expected \"" << c.expect << "\" in: " << err;
    EXPECT_TRUE(out.empty());
  }
}

}  // namespace
}  // namespace blvd::package
