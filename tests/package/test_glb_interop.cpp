// Interoperability: our GLBs, read by an independent glTF loader (tinygltf
// 2.7 with its own Draco path), must give the same geometry. Only our own,
// well-formed output goes through tinygltf here: its Draco path is not safe on
// untrusted input (see sdk/package/glb.cpp), which is why the SDK does not
// use it.
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_ENABLE_DRACO
#define TINYGLTF_NO_STB_IMAGE        // the stb implementation lives in sdk/render
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <cmath>
#include <cstring>

#include "package/glb.h"

namespace blvd::package {
namespace {

geo::MeshData grid(int n) {
  geo::MeshData m;
  for (int z = 0; z <= n; ++z)
    for (int x = 0; x <= n; ++x) {
      m.positions.insert(m.positions.end(), {x * 0.5f, std::sin(x * 0.3f) * std::cos(z * 0.2f), -z * 0.5f});
      m.normals.insert(m.normals.end(), {0.0f, 1.0f, 0.0f});
      m.colors.insert(m.colors.end(), {uint8_t(x * 9), uint8_t(z * 9), 128, 255});
    }
  for (int z = 0; z < n; ++z)
    for (int x = 0; x < n; ++x) {
      const uint32_t a = z * (n + 1) + x, b = a + 1, c = a + (n + 1), d = c + 1;
      m.indices.insert(m.indices.end(), {a, b, d, a, d, c});
    }
  return m;
}

// Reads accessor `i` as floats through tinygltf's own model.
std::vector<float> floats(const tinygltf::Model& model, int i, int comps) {
  const tinygltf::Accessor& a = model.accessors.at(i);
  const tinygltf::BufferView& v = model.bufferViews.at(a.bufferView);
  const tinygltf::Buffer& b = model.buffers.at(v.buffer);
  const int stride = a.ByteStride(v);
  std::vector<float> out;
  for (size_t e = 0; e < a.count; ++e) {
    const unsigned char* p = b.data.data() + v.byteOffset + a.byteOffset + e * stride;
    for (int k = 0; k < comps; ++k) {
      float f = 0;
      if (a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT) std::memcpy(&f, p + 4 * k, 4);
      else if (a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) f = p[k] / 255.0f;
      out.push_back(f);
    }
  }
  return out;
}

TEST(GlbInterop, TinygltfReadsOurOutput) {
  const geo::MeshData src = grid(30);
  // tinygltf 2.7 has no EXT_meshopt_compression (test_glb_meshopt.cpp checks
  // our meshopt output against the extension's rules instead).
  for (GlbCodec codec : {GlbCodec::Plain, GlbCodec::Draco}) {
    GlbOptions opt;
    opt.codec = codec;
    const std::vector<uint8_t> glb = encodeGlb(src, opt);
    tinygltf::TinyGLTF loader;
    tinygltf::Model model;
    std::string err, warn;
    ASSERT_TRUE(loader.LoadBinaryFromMemory(&model, &err, &warn, glb.data(), static_cast<unsigned>(glb.size())))
        << err;
    EXPECT_TRUE(err.empty()) << err;
    ASSERT_EQ(model.meshes.size(), 1u);
    const tinygltf::Primitive& prim = model.meshes[0].primitives.at(0);
    EXPECT_EQ(prim.mode, TINYGLTF_MODE_TRIANGLES);
    EXPECT_EQ(codec == GlbCodec::Draco, prim.extensions.count("KHR_draco_mesh_compression") == 1);
    const std::vector<float> pos = floats(model, prim.attributes.at("POSITION"), 3);
    const std::vector<float> col = floats(model, prim.attributes.at("COLOR_0"), 4);
    const tinygltf::Accessor& ia = model.accessors.at(prim.indices);
    ASSERT_EQ(ia.count, src.indices.size());
    ASSERT_EQ(pos.size(), src.positions.size());  // Draco keeps this grid's vertex count
    // Same triangles: compare each triangle's corner positions via indices
    // (Draco may reorder, so match through our own decoder's output).
    geo::MeshData ours;
    ASSERT_EQ(decodeGlb(glb.data(), glb.size(), ours, err), core::Status::Ok) << err;
    ASSERT_EQ(ours.positions.size(), pos.size());
    for (size_t i = 0; i < pos.size(); ++i) EXPECT_NEAR(pos[i], ours.positions[i], 1e-6f) << i;
    // Positions stay within the accessor's min/max, which viewers use for bounds.
    const tinygltf::Accessor& pa = model.accessors.at(prim.attributes.at("POSITION"));
    ASSERT_EQ(pa.minValues.size(), 3u);
    for (size_t i = 0; i < pos.size(); ++i) {
      EXPECT_GE(pos[i], pa.minValues[i % 3] - 1e-6);
      EXPECT_LE(pos[i], pa.maxValues[i % 3] + 1e-6);
    }
    // Colour is linear in the file; alpha passes through.
    for (size_t v = 0; v < col.size() / 4; ++v) EXPECT_FLOAT_EQ(col[v * 4 + 3], 1.0f);
    ASSERT_EQ(model.materials.size(), 1u);
    EXPECT_EQ(model.materials[0].pbrMetallicRoughness.baseColorFactor, std::vector<double>({1, 1, 1, 1}));
    EXPECT_EQ(model.materials[0].pbrMetallicRoughness.roughnessFactor, 1.0);
    EXPECT_EQ(model.materials[0].pbrMetallicRoughness.metallicFactor, 0.0);
  }
}

}  // namespace
}  // namespace blvd::package
