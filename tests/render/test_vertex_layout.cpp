// The renderer's 20-byte vertex (prepared_mesh.h): the position relative to
// the mesh's box centre, then an untextured mesh's unit normal (signed
// normalised bytes) and colour, or a textured mesh's uv, in the same 8 bytes.
// The bytes are read back as the GL attribute pointers read them.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "render/prepared_mesh.h"
#include "scene.h"
#include <stb/stb_image_write.h>

namespace blvd::render {
namespace {

struct Read {
  glm::vec3 position;
  glm::vec3 normal;  // as GL_BYTE, normalised: max(c / 127, -1)
  std::array<uint8_t, 4> color;
  glm::vec2 uv;
};

Read vertex(const PreparedMesh& p, uint32_t i) {
  const uint8_t* v = p.vertices + size_t(i) * kVertexBytes;
  Read r;
  std::memcpy(&r.position, v, 12);
  for (int k = 0; k < 3; ++k) r.normal[k] = std::max(float(static_cast<int8_t>(v[12 + k])) / 127.0f, -1.0f);
  std::memcpy(r.color.data(), v + 16, 4);
  std::memcpy(&r.uv, v + 12, 8);
  return r;
}

bool prepare(const geo::MeshData& m, std::vector<uint8_t>& block, PreparedMesh& p, int tw = 0, int th = 0) {
  block.assign(preparedBytes(m.vertexCount(), m.indices.size(), tw, th), 0);
  StagingArena arena{block.data(), block.size(), 0};
  std::string err;
  const bool ok = prepareMesh(m, arena, p, err);
  EXPECT_TRUE(ok) << err;
  return ok;
}

TEST(VertexLayout, AnUntexturedVertexHoldsItsPositionNormalAndColourIn20Bytes) {
  EXPECT_EQ(kVertexBytes, 20u);
  const uint8_t rgba[4] = {10, 120, 250, 255};
  geo::MeshData m = test::makeFlat(2, 4, 6, 10, 3, rgba);
  const glm::vec3 n = glm::normalize(glm::vec3(0.3f, 0.8f, -0.52f));
  for (int i = 0; i < 4; ++i) m.normals.insert(m.normals.end(), {n.x, n.y, n.z});
  std::vector<uint8_t> block;
  PreparedMesh p;
  ASSERT_TRUE(prepare(m, block, p));
  // Centre (4, 3, 7): vertex 0 is (2, 3, 10).
  const Read r = vertex(p, 0);
  EXPECT_EQ(r.position, glm::vec3(-2, 0, 3));
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(r.normal[k], n[k], 0.5f / 127.0f) << k;
  EXPECT_EQ(r.color, (std::array<uint8_t, 4>{10, 120, 250, 255}));
  EXPECT_EQ(vertex(p, 2).position, glm::vec3(2, 0, -3));
  EXPECT_EQ(p.vertexBytes(), 4u * 20u);
}

// Without normals of its own a mesh gets each vertex's area-weighted sum of
// its triangles' normals; a non-unit normal it brings is made unit.
TEST(VertexLayout, NormalsAMeshLacksAreTheAreaWeightedFaceNormals) {
  geo::MeshData tent;
  // Two triangles sharing the edge (0,0,0)-(0,0,1), one reaching to x = 1,
  // the other, with 2.9 times its area, to x = −4: their area-weighted sum
  // points straight up, where an unweighted mean of unit normals would not.
  tent.positions = {0, 0, 0, 0, 0, 1, 1, 1, 0, -4, 1, 0};
  tent.indices = {0, 1, 2, 0, 3, 1};
  std::vector<uint8_t> block;
  PreparedMesh p;
  ASSERT_TRUE(prepare(tent, block, p));
  const glm::vec3 a(0, 0, 0), b(0, 0, 1), c(1, 1, 0), d(-4, 1, 0);
  const glm::vec3 n1 = glm::cross(b - a, c - a), n2 = glm::cross(d - a, b - a);
  const glm::vec3 shared = glm::normalize(n1 + n2);
  for (uint32_t i : {0u, 1u}) {
    const Read r = vertex(p, i);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(r.normal[k], shared[k], 0.5f / 127.0f) << i << " " << k;
    EXPECT_EQ(r.color, (std::array<uint8_t, 4>{200, 200, 200, 255}));  // no colour: light grey
  }
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(vertex(p, 2).normal[k], glm::normalize(n1)[k], 0.5f / 127.0f);
  // Positions are written after the sums that borrowed their place.
  EXPECT_EQ(vertex(p, 3).position, glm::vec3(-2.5f, 0.5f, -0.5f));

  tent.normals = {0, 5, 0, 0, 0, 0, 3, 0, 4, 0, -2, 0};
  ASSERT_TRUE(prepare(tent, block, p));
  EXPECT_EQ(vertex(p, 0).normal, glm::vec3(0, 1, 0));
  EXPECT_EQ(vertex(p, 1).normal, glm::vec3(0, 1, 0));  // zero length: up
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(vertex(p, 2).normal[k], glm::vec3(0.6f, 0, 0.8f)[k], 0.5f / 127.0f);
  EXPECT_EQ(vertex(p, 3).normal, glm::vec3(0, -1, 0));
}

TEST(VertexLayout, ATexturedVertexHoldsItsUvExactly) {
  const uint8_t white[4] = {255, 255, 255, 255};
  geo::MeshData m = test::makeFlat(0, 0, 1, 1, 0, white);
  m.texcoords = {0.123456f, 0.987654f, 1, 0, 1, 1, 1.0f / 3.0f, 2.0f / 3.0f};
  // A 1 × 1 PNG, as a glTF would embed it.
  stbi_write_png_to_func(
      [](void* ctx, void* data, int size) {
        auto* v = static_cast<std::vector<uint8_t>*>(ctx);
        v->insert(v->end(), static_cast<uint8_t*>(data), static_cast<uint8_t*>(data) + size);
      },
      &m.image, 1, 1, 4, white, 4);
  std::vector<uint8_t> block;
  PreparedMesh p;
  ASSERT_TRUE(prepare(m, block, p, 1, 1));
  ASSERT_NE(p.rgba, nullptr);
  EXPECT_EQ(vertex(p, 0).uv, glm::vec2(0.123456f, 0.987654f));
  EXPECT_EQ(vertex(p, 3).uv, glm::vec2(1.0f / 3.0f, 2.0f / 3.0f));
  EXPECT_EQ(vertex(p, 0).position, glm::vec3(-0.5f, 0, 0.5f));
}

}  // namespace
}  // namespace blvd::render
