// GLB codec: round trips with and without Draco, the Khronos Box in both
// encodings, node transforms, and bad input (every truncation, byte flips,
// garbage) returning errors instead of crashing.
#include "package/glb.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>

#include "glb_test_util.h"
#include "package_test_util.h"

namespace blvd::package {
namespace {

using core::Status;
using geo::MeshData;
using namespace glbtest;

TEST(Glb, RoundTripPlain) {
  const MeshData src = box();
  GlbOptions opt;
  opt.codec = GlbCodec::Plain;
  const std::vector<uint8_t> glb = encodeGlb(src, opt);
  const auto doc = glbJson(glb);
  EXPECT_FALSE(doc.contains("extensionsUsed"));
  EXPECT_EQ(doc["accessors"][0]["min"], nlohmann::json({-1.0, -0.5, -1.5}));
  EXPECT_EQ(doc["accessors"][0]["max"], nlohmann::json({1.0, 0.5, 1.5}));
  EXPECT_EQ(doc["materials"][0]["pbrMetallicRoughness"]["roughnessFactor"], 1.0);
  MeshData out;
  std::string err;
  ASSERT_EQ(decodeGlb(glb.data(), glb.size(), out, err), Status::Ok) << err;
  EXPECT_EQ(out.positions, src.positions);  // plain buffers keep order and bits
  EXPECT_EQ(out.normals, src.normals);
  EXPECT_EQ(out.indices, src.indices);
  ASSERT_EQ(out.colors.size(), src.colors.size());
  for (size_t i = 0; i < src.colors.size(); ++i)
    EXPECT_NEAR(out.colors[i], src.colors[i], i % 4 == 3 ? 0 : colorTolerance(src.colors[i])) << i;
}

TEST(Glb, RoundTripDraco) {
  const MeshData src = box();
  const std::vector<uint8_t> glb = encodeGlb(src);
  const auto doc = glbJson(glb);
  EXPECT_EQ(doc["extensionsUsed"], nlohmann::json({"KHR_draco_mesh_compression"}));
  EXPECT_EQ(doc["extensionsRequired"], nlohmann::json({"KHR_draco_mesh_compression"}));
  for (const auto& acc : doc["accessors"]) {
    EXPECT_FALSE(acc.contains("bufferView")) << acc.dump();
    EXPECT_TRUE(acc.contains("count") && acc.contains("componentType") && acc.contains("type"));
  }
  const auto& prim = doc["meshes"][0]["primitives"][0];
  EXPECT_TRUE(prim["extensions"]["KHR_draco_mesh_compression"]["attributes"].contains("COLOR_0"));
  EXPECT_TRUE(doc["accessors"][prim["attributes"]["POSITION"].get<int>()].contains("min"));
  MeshData out;
  std::string err;
  ASSERT_EQ(decodeGlb(glb.data(), glb.size(), out, err), Status::Ok) << err;
  EXPECT_EQ(out.vertexCount(), src.vertexCount());
  EXPECT_EQ(out.triangleCount(), src.triangleCount());
  // 16-bit quantization over a 3 m extent: steps of 3/65535 m.
  const float pos_tol = 3.0f / 65535 * 1.01f;
  expectSameTriangles(src, out, pos_tol);
  // 10-bit octahedral normals, 8-bit linear colours.
  expectSameAttributes(src, out, pos_tol, 0.01f);
}

TEST(Glb, DracoOptions) {
  const MeshData src = box(20, 10, 30, 100, 5, -40);
  for (int level : {0, 5, 10}) {
    for (int bits : {0, 11, 20}) {
      GlbOptions opt;
      opt.compression_level = level;
      opt.position_bits = bits;
      const auto glb = encodeGlb(src, opt);
      MeshData out;
      std::string err;
      ASSERT_EQ(decodeGlb(glb.data(), glb.size(), out, err), Status::Ok) << err;
      const float tol = bits == 0 ? 0.0f : 30.0f / float((1 << bits) - 1) * 1.01f;
      expectSameTriangles(src, out, tol);
    }
  }
  GlbOptions bad;
  bad.position_bits = 31;
  EXPECT_THROW(encodeGlb(src, bad), core::Error);
  bad = GlbOptions{};
  bad.compression_level = 11;
  EXPECT_THROW(encodeGlb(src, bad), core::Error);
}

TEST(Glb, NoNormalsNoColors) {
  MeshData src = box();
  src.normals.clear();
  src.colors.clear();
  for (GlbCodec codec : {GlbCodec::Plain, GlbCodec::Draco, GlbCodec::Meshopt}) {
    GlbOptions opt;
    opt.codec = codec;
    const auto glb = encodeGlb(src, opt);
    MeshData out;
    std::string err;
    ASSERT_EQ(decodeGlb(glb.data(), glb.size(), out, err), Status::Ok) << err;
    // Flat normals unweld: three vertices per triangle, facing outwards.
    EXPECT_EQ(out.vertexCount(), src.triangleCount() * 3);
    expectSameTriangles(src, out, 3.0f / 65535 * 1.01f);
    for (size_t v = 0; v < out.vertexCount(); ++v) {
      float dot = 0;
      for (int a = 0; a < 3; ++a) dot += out.normals[v * 3 + a] * out.positions[v * 3 + a];
      EXPECT_GT(dot, 0) << "normal of vertex " << v << " points inwards";
    }
    EXPECT_TRUE(std::all_of(out.colors.begin(), out.colors.end(), [](uint8_t c) { return c == 255; }));
  }
}

TEST(Glb, EmptyMesh) {
  for (GlbCodec codec : {GlbCodec::Plain, GlbCodec::Draco, GlbCodec::Meshopt}) {
    GlbOptions opt;
    opt.codec = codec;
    const auto glb = encodeGlb(MeshData{}, opt);
    const auto doc = glbJson(glb);
    EXPECT_EQ(doc["scenes"].size(), 1u);
    MeshData out = box();
    std::string err;
    ASSERT_EQ(decodeGlb(glb.data(), glb.size(), out, err), Status::Ok) << err;
    EXPECT_TRUE(out.empty());
    EXPECT_EQ(out.vertexCount(), 0u);
  }
}

TEST(Glb, LargeIndicesUseUint32) {
  // A strip of quads with more than 65535 vertices.
  MeshData m;
  const uint32_t n = 70000;
  for (uint32_t i = 0; i < n; ++i) {
    m.positions.insert(m.positions.end(), {float(i / 2), 0.0f, float(i % 2)});
    m.normals.insert(m.normals.end(), {0.0f, 1.0f, 0.0f});
    m.colors.insert(m.colors.end(), {uint8_t(i), uint8_t(i >> 8), 7, 255});
  }
  for (uint32_t i = 0; i + 3 < n; i += 2) m.indices.insert(m.indices.end(), {i, i + 1, i + 3, i, i + 3, i + 2});
  for (GlbCodec codec : {GlbCodec::Plain, GlbCodec::Draco, GlbCodec::Meshopt}) {
    GlbOptions opt;
    opt.codec = codec;
    const auto glb = encodeGlb(m, opt);
    const auto doc = glbJson(glb);
    EXPECT_EQ(doc["accessors"][doc["meshes"][0]["primitives"][0]["indices"].get<int>()]["componentType"], 5125);
    MeshData out;
    std::string err;
    ASSERT_EQ(decodeGlb(glb.data(), glb.size(), out, err), Status::Ok) << err;
    EXPECT_EQ(out.triangleCount(), m.triangleCount());
    EXPECT_EQ(out.vertexCount(), m.vertexCount());
  }
}

// Textured meshes (impostors): TEXCOORD_0 and an embedded PNG/JPEG survive
// both encodings; the image type comes from its bytes.
TEST(Glb, TexcoordsAndImage) {
  MeshData src = box();
  for (size_t v = 0; v < src.vertexCount(); ++v) src.texcoords.insert(src.texcoords.end(), {(v % 4) * 0.25f, (v / 4) / 6.0f});
  src.image = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n', 1, 2, 3};
  src.image_mime = "image/png";
  for (GlbCodec codec : {GlbCodec::Plain, GlbCodec::Draco, GlbCodec::Meshopt}) {
    GlbOptions opt;
    opt.codec = codec;
    const auto glb = encodeGlb(src, opt);
    MeshData out;
    std::string err;
    ASSERT_EQ(decodeGlb(glb.data(), glb.size(), out, err), Status::Ok) << err;
    ASSERT_EQ(out.texcoords.size(), out.vertexCount() * 2);
    EXPECT_EQ(out.image, src.image);
    EXPECT_EQ(out.image_mime, "image/png");
    if (codec == GlbCodec::Plain) {
      EXPECT_EQ(out.texcoords, src.texcoords);
    }
  }
  // A non-image payload is dropped, the geometry still decodes.
  src.image = {'G', 'I', 'F', '8', '9', 'a'};
  src.image_mime = "image/jpeg";  // the encoder trusts the caller; the decoder checks the bytes
  GlbOptions plain;
  plain.codec = blvd::package::GlbCodec::Plain;
  auto glb = encodeGlb(src, plain);
  MeshData out;
  std::string err;
  ASSERT_EQ(decodeGlb(glb.data(), glb.size(), out, err), Status::Ok) << err;
  EXPECT_TRUE(out.image.empty());
  EXPECT_EQ(out.triangleCount(), 12u);
  // Non-finite uvs in a file are refused (the encoder refuses them too).
  src.image.clear();
  glb = encodeGlb(src, plain);
  const auto doc = glbJson(glb);
  const int tex_acc = doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"].get<int>();
  const size_t at = 20 + 8 + doc["bufferViews"][doc["accessors"][tex_acc]["bufferView"].get<int>()]["byteOffset"].get<size_t>();
  uint32_t json_len;
  std::memcpy(&json_len, glb.data() + 12, 4);
  const float inf = std::numeric_limits<float>::infinity();
  std::memcpy(glb.data() + json_len + at, &inf, 4);
  EXPECT_EQ(decodeGlb(glb.data(), glb.size(), out, err), Status::Corrupt);
  EXPECT_NE(err.find("TEXCOORD_0 element 0 is not finite"), std::string::npos) << err;
}

// A WebP image is the texture's source through EXT_texture_webp, required (no
// fallback image), and comes back as image/webp from its RIFF/WEBP bytes.
TEST(Glb, WebpImageThroughExtTextureWebp) {
  MeshData src = box();
  for (size_t v = 0; v < src.vertexCount(); ++v) src.texcoords.insert(src.texcoords.end(), {0.5f, 0.5f});
  src.image = {'R', 'I', 'F', 'F', 20, 0, 0, 0, 'W', 'E', 'B', 'P', 'V', 'P', '8', ' ', 1, 2, 3, 4};
  src.image_mime = "image/webp";
  for (GlbCodec codec : {GlbCodec::Plain, GlbCodec::Draco, GlbCodec::Meshopt}) {
    GlbOptions opt;
    opt.codec = codec;
    const auto glb = encodeGlb(src, opt);
    const auto doc = glbJson(glb);
    EXPECT_EQ(doc["textures"][0]["extensions"]["EXT_texture_webp"]["source"], 0);
    EXPECT_FALSE(doc["textures"][0].contains("source"));
    const auto& req = doc["extensionsRequired"];
    EXPECT_NE(std::find(req.begin(), req.end(), "EXT_texture_webp"), req.end()) << req.dump();
    MeshData out;
    std::string err;
    ASSERT_EQ(decodeGlb(glb.data(), glb.size(), out, err), Status::Ok) << err;
    EXPECT_EQ(out.image, src.image);
    EXPECT_EQ(out.image_mime, "image/webp");
  }
}

TEST(Glb, InvalidMeshIsRefused) {
  MeshData m = box();
  m.indices.back() = 24;
  try {
    encodeGlb(m);
    FAIL();
  } catch (const core::Error& e) {
    EXPECT_EQ(e.status(), Status::InvalidArg);
    EXPECT_NE(std::string(e.what()).find("index 35 = 24 >= vertex count 24"), std::string::npos) << e.what();
  }
  m = box();
  m.colors.pop_back();
  EXPECT_THROW(encodeGlb(m), core::Error);
  m = box();
  m.positions[4] = std::nanf("");
  EXPECT_THROW(encodeGlb(m), core::Error);
}

MeshData decodeFile(const std::string& path) {
  const auto bytes = testutil::readFile(path);
  EXPECT_FALSE(bytes.empty()) << path;
  MeshData m;
  std::string err;
  EXPECT_EQ(decodeGlb(bytes.data(), bytes.size(), m, err), Status::Ok) << path << ": " << err;
  return m;
}

// Khronos' Box, plain, decodes; its Draco version (from Google's draco
// repository) stores the box's positions as a Draco POSITION attribute, which
// our decoder refuses before any attribute value is decoded (draco_decode.cpp:
// with one, Draco 1.5.5 decodes a texture-coordinate prediction without
// bound). The box re-encoded by our own Draco encoder decodes to the same
// triangles.
TEST(Glb, KhronosBoxPlainDecodesAndItsDracoPositionIsRefused) {
  const MeshData plain = decodeFile(BLVD_TEST_DATA_DIR "/gltf/Box.glb");
  EXPECT_EQ(plain.triangleCount(), 12u);
  EXPECT_EQ(plain.vertexCount(), 24u);
  // The node's matrix turns Z-up into Y-up: the unit box stays a unit box.
  for (size_t i = 0; i < plain.positions.size(); ++i) EXPECT_NEAR(std::fabs(plain.positions[i]), 0.5f, 1e-6f);
  // The material is red (0.8, 0, 0) linear: vertex colours carry it, in sRGB.
  EXPECT_EQ(plain.colors[0], 231);
  EXPECT_EQ(plain.colors[1], 0);

  const auto khronos = testutil::readFile(BLVD_TEST_DATA_DIR "/gltf/Box_Draco.glb");
  ASSERT_FALSE(khronos.empty());
  MeshData refused;
  std::string err;
  EXPECT_EQ(decodeGlb(khronos.data(), khronos.size(), refused, err), Status::Unsupported);
  EXPECT_NE(err.find("KHR_draco_mesh_compression: Draco data declares a POSITION attribute"), std::string::npos) << err;
  EXPECT_TRUE(refused.empty());

  const std::vector<uint8_t> own = encodeGlb(plain);
  MeshData draco;
  ASSERT_EQ(decodeGlb(own.data(), own.size(), draco, err), Status::Ok) << err;
  EXPECT_EQ(draco.triangleCount(), 12u);
  expectSameTriangles(plain, draco, 1e-3f);
  EXPECT_EQ(draco.colors[0], 231);
  // Normals stay unit length and point out of the box.
  for (size_t v = 0; v < draco.vertexCount(); ++v) {
    float dot = 0, len = 0;
    for (int a = 0; a < 3; ++a) {
      dot += draco.normals[v * 3 + a] * draco.positions[v * 3 + a];
      len += draco.normals[v * 3 + a] * draco.normals[v * 3 + a];
    }
    EXPECT_GT(dot, 0);
    EXPECT_NEAR(len, 1.0f, 1e-3f);
  }
}

// A hand-made GLB: one triangle instanced by two nodes, one mirrored
// (scale -1 on x) and translated, with TRS; the mirrored copy must keep
// facing the same way (winding flipped), and normals follow.
TEST(Glb, NodeTransforms) {
  std::vector<uint8_t> bin(36 + 36 + 6 + 2);
  const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const float nrm[9] = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  const uint16_t idx[3] = {0, 1, 2};
  std::memcpy(bin.data(), pos, 36);
  std::memcpy(bin.data() + 36, nrm, 36);
  std::memcpy(bin.data() + 72, idx, 6);
  const std::string json = R"({
    "asset": {"version": "2.0"}, "scene": 0,
    "scenes": [{"nodes": [0, 1]}],
    "nodes": [{"mesh": 0, "translation": [10, 0, 0]},
              {"children": [2], "scale": [-1, 1, 1]},
              {"mesh": 0, "translation": [0, 0, 5], "rotation": [0, 0, 0, 1]}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2}]}],
    "accessors": [
      {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
      {"bufferView": 0, "byteOffset": 36, "componentType": 5126, "count": 3, "type": "VEC3"},
      {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}],
    "bufferViews": [{"buffer": 0, "byteLength": 72}, {"buffer": 0, "byteOffset": 72, "byteLength": 6}],
    "buffers": [{"byteLength": 80}]})";
  const auto glb = makeGlb(json, bin);
  MeshData out;
  std::string err;
  ASSERT_EQ(decodeGlb(glb.data(), glb.size(), out, err), Status::Ok) << err;
  ASSERT_EQ(out.triangleCount(), 2u);
  ASSERT_EQ(out.vertexCount(), 6u);
  EXPECT_FLOAT_EQ(out.positions[3], 11.0f);  // node 0, vertex 1: x = 1 + 10
  EXPECT_FLOAT_EQ(out.positions[9 + 3], -1.0f);  // node 2 under the mirror: x = -1
  EXPECT_FLOAT_EQ(out.positions[9 + 5], 5.0f);
  // Geometric normal of each output triangle agrees with its vertex normal.
  for (int t = 0; t < 2; ++t) {
    const float* p0 = &out.positions[out.indices[t * 3] * 3];
    const float* p1 = &out.positions[out.indices[t * 3 + 1] * 3];
    const float* p2 = &out.positions[out.indices[t * 3 + 2] * 3];
    const float u[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]}, w[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
    const float gz = u[0] * w[1] - u[1] * w[0];
    EXPECT_GT(gz * out.normals[out.indices[t * 3] * 3 + 2], 0) << "triangle " << t;
  }
}

TEST(Glb, ErrorsNameWhatFailed) {
  std::vector<uint8_t> bin(36);
  const float one = 1.0f;  // bytes 00 00 80 3F: read as ubyte indices 0, 0, 128
  std::memcpy(bin.data() + 32, &one, 4);
  struct Case {
    const char* json;
    const char* expect;
    Status status;
  };
  const Case cases[] = {
      {R"({"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
          "accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3"}],
          "bufferViews":[{"buffer":0,"byteLength":36}],"buffers":[{"byteLength":36}]})",
       "accessors[0] (POSITION): 4 elements of 12 bytes at offset 0 run past the bufferView (36 bytes)", Status::Corrupt},
      {R"({"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attributes":{"POSITION":3}}]}]})",
       "meshes[0].primitives[0].attributes.POSITION: index 3 out of range (accessors has 0)", Status::Corrupt},
      {R"({"asset":{"version":"2.0"},"bufferViews":[{"buffer":0,"byteOffset":40,"byteLength":8}],"buffers":[{"byteLength":36}],
          "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
          "accessors":[{"bufferView":0,"componentType":5126,"count":1,"type":"VEC3"}]})",
       "bufferViews[0]: byteOffset 40 + byteLength 8 runs past buffers[0] (36 bytes)", Status::Corrupt},
      {R"({"asset":{"version":"2.0"},"extensionsRequired":["EXT_mesh_gpu_instancing"]})",
       "extensionsRequired: EXT_mesh_gpu_instancing is not supported", Status::Unsupported},
      {R"({"asset":{"version":"2.0"},"buffers":[{"byteLength":8,"uri":"../../etc/passwd"}],
          "bufferViews":[{"buffer":0,"byteLength":8}],"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
          "accessors":[{"bufferView":0,"componentType":5126,"count":0,"type":"VEC3"}]})",
       "is not supported in a GLB", Status::Unsupported},
      {R"({"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"children":[0]}]})",
       "deeper than 64", Status::Corrupt},
      {R"({"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],
          "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"},
                       {"bufferView":1,"componentType":5121,"count":3,"type":"SCALAR"}],
          "bufferViews":[{"buffer":0,"byteLength":36},{"buffer":0,"byteOffset":32,"byteLength":4}],
          "buffers":[{"byteLength":36}]})",
       "index 2 = 128 >= vertex count 3", Status::Corrupt},
      {R"({"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
          "accessors":[{"bufferView":0,"componentType":5126,"count":-1,"type":"VEC3"}]})",
       "accessors[0].count: expected a non-negative integer", Status::Corrupt},
      {R"({"asset":{"version":"2.0"}, "meshes": [1, 2)", "JSON", Status::Corrupt},
  };
  for (const Case& c : cases) {
    const auto glb = makeGlb(c.json, bin);
    MeshData out;
    std::string err;
    EXPECT_EQ(decodeGlb(glb.data(), glb.size(), out, err), c.status) << c.json << "\n" << err;
    EXPECT_NE(err.find(c.expect), std::string::npos) << "expected \"" << c.expect << "\" in: " << err;
    EXPECT_TRUE(out.empty());
  }
}

TEST(Glb, EveryTruncationFails) {
  GlbOptions meshopt;
  meshopt.codec = GlbCodec::Meshopt;
  for (const std::string& path :
       {std::string(BLVD_TEST_DATA_DIR "/gltf/Box_Draco.glb"), std::string("own"), std::string("own meshopt")}) {
    const std::vector<uint8_t> glb = path == "own"           ? encodeGlb(box())
                                     : path == "own meshopt" ? encodeGlb(box(), meshopt)
                                                             : testutil::readFile(path);
    ASSERT_FALSE(glb.empty());
    for (size_t n = 0; n < glb.size(); ++n) {
      // A fresh copy of exactly n bytes, so ASan sees any read past the end.
      std::vector<uint8_t> cut(glb.begin(), glb.begin() + static_cast<ptrdiff_t>(n));
      MeshData out;
      std::string err;
      EXPECT_NE(decodeGlb(n ? cut.data() : nullptr, n, out, err), Status::Ok) << path << " at " << n;
      EXPECT_FALSE(err.empty());
    }
  }
}

// The GLB length fields are fixed up after truncating the Draco bitstream,
// the meshopt views or the JSON, so the damage reaches Draco, meshoptimizer
// and the JSON reader themselves.
class GlbDamage : public ::testing::TestWithParam<GlbCodec> {};

TEST_P(GlbDamage, DamagedPayloadsNeverCrash) {
  GlbOptions opt;
  opt.codec = GetParam();
  const std::vector<uint8_t> glb = encodeGlb(box(), opt);
  uint32_t json_len;
  std::memcpy(&json_len, glb.data() + 12, 4);
  const size_t bin_start = 20 + json_len + 8;
  uint32_t bin_len;
  std::memcpy(&bin_len, glb.data() + 20 + json_len, 4);
  const std::string json(glb.begin() + 20, glb.begin() + 20 + json_len);
  const std::vector<uint8_t> bin(glb.begin() + static_cast<ptrdiff_t>(bin_start), glb.end());
  size_t ok = 0, failed = 0;
  auto run = [&](const std::vector<uint8_t>& g) {
    MeshData out;
    std::string err;
    if (decodeGlb(g.data(), g.size(), out, err) == Status::Ok) {
      ++ok;
      for (uint32_t i : out.indices) ASSERT_LT(i, out.vertexCount());
    } else {
      ++failed;
      EXPECT_FALSE(err.empty());
    }
  };
  for (size_t n = 0; n < bin.size(); ++n) run(makeGlb(json, std::vector<uint8_t>(bin.begin(), bin.begin() + n)));
  for (size_t i = 0; i < bin.size(); ++i)
    for (uint8_t mask : {uint8_t{0x01}, uint8_t{0x10}, uint8_t{0xFF}}) {
      std::vector<uint8_t> b = bin;
      b[i] ^= mask;
      run(makeGlb(json, b));
    }
  for (size_t i = 0; i < json.size(); ++i) {
    std::string j = json;
    j[i] = static_cast<char>(j[i] ^ 0x04);
    run(makeGlb(j, bin));
    run(makeGlb(json.substr(0, i), bin));
  }
  EXPECT_GT(failed, 0u);
  EXPECT_GT(ok, 0u);  // flips in harmless places (e.g. "generator") still decode
}

INSTANTIATE_TEST_SUITE_P(Codecs, GlbDamage, ::testing::Values(GlbCodec::Draco, GlbCodec::Meshopt),
                         [](const ::testing::TestParamInfo<GlbCodec>& i) { return std::string(glbCodecName(i.param)); });

TEST(Glb, GarbageNeverCrashes) {
  std::mt19937 rng(12345);
  for (int round = 0; round < 2000; ++round) {
    std::vector<uint8_t> g(rng() % 300);
    for (auto& b : g) b = static_cast<uint8_t>(rng());
    if (round % 2 && g.size() >= 20) {  // plausible header, random rest
      const uint32_t hdr[5] = {0x46546C67, 2, static_cast<uint32_t>(g.size()), static_cast<uint32_t>(rng() % g.size()), 0x4E4F534A};
      std::memcpy(g.data(), hdr, 20);
    }
    MeshData out;
    std::string err;
    EXPECT_NE(decodeGlb(g.data(), g.size(), out, err), Status::Ok);
  }
  const auto pbf = testutil::readFile(BLVD_DATA_DIR "/osm/monaco-geofabrik-2026.osm.pbf");
  MeshData out;
  std::string err;
  EXPECT_EQ(decodeGlb(pbf.data(), pbf.size(), out, err), Status::Corrupt);
  EXPECT_NE(err.find("bad magic"), std::string::npos) << err;
}

// What a fuzz campaign found (tests/fuzz/regressions/fuzz_glb): an impostor
// GLB whose 262-byte Draco stream predicts an attribute with Draco's texture
// coordinate scheme and an orientation count of about 2^31. Draco 1.5.5
// decoded it for 10 s of CPU and 434 MB (ASan build); it is refused at its
// attribute declarations now.
TEST(Glb, AnUnboundedDracoPredictionIsRefusedBeforeItRuns) {
  const auto glb = testutil::readFile(BLVD_TEST_DATA_DIR
                                      "/../fuzz/regressions/fuzz_glb/timeout-db4afedee76815f4dda1e856d2b28d3b0e79e382");
  ASSERT_EQ(glb.size(), 1612u);
  MeshData out;
  std::string err;
  EXPECT_EQ(decodeGlb(glb.data(), glb.size(), out, err), Status::Unsupported);
  EXPECT_NE(err.find("Draco data declares a POSITION attribute"), std::string::npos) << err;
}

// Our Draco streams keep to the profile the decoder reads: no attribute of
// Draco type POSITION, whatever the compression level (from level 5 up, Draco's
// edgebreaker would build per-attribute connectivity around a POSITION: the
// encoder splits the mesh on seams instead).
TEST(Glb, OwnDracoStreamsHoldNoPositionTypedAttribute) {
  MeshData m = box();
  for (size_t v = 0; v < m.vertexCount(); ++v) m.texcoords.insert(m.texcoords.end(), {(v % 4) * 0.25f, (v / 4) / 6.0f});
  for (int level : {0, 3, 7, 10}) {
    GlbOptions opt;
    opt.compression_level = level;
    const std::vector<uint8_t> glb = encodeGlb(m, opt);
    MeshData out;
    std::string err;
    ASSERT_EQ(decodeGlb(glb.data(), glb.size(), out, err), Status::Ok) << "level " << level << ": " << err;
    expectSameTriangles(m, out, 1e-3f);
    EXPECT_EQ(out.texcoords.size(), out.vertexCount() * 2);
  }
}

}  // namespace
}  // namespace blvd::package
