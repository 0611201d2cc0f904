// Helpers shared by the GLB tests: a box mesh, meshes compared as triangle
// sets (codecs reorder), a GLB's JSON, and hand-made GLBs.
#pragma once
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "geo/mesh.h"

namespace blvd::package::glbtest {

using geo::MeshData;

// A w x h x d box with 24 vertices (flat normals per face) and per-face colours.
inline MeshData box(float w = 2, float h = 1, float d = 3, float cx = 0, float cy = 0, float cz = 0) {
  MeshData m;
  struct Face {
    std::array<float, 3> n, u, v;
    std::array<uint8_t, 4> c;
  };
  const Face faces[6] = {
      {{1, 0, 0}, {0, 0, -1}, {0, 1, 0}, {200, 30, 30, 255}},  {{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}, {30, 200, 30, 255}},
      {{0, 1, 0}, {1, 0, 0}, {0, 0, -1}, {30, 30, 200, 255}},  {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}, {128, 128, 128, 255}},
      {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}, {10, 20, 240, 128}},   {{0, 0, -1}, {-1, 0, 0}, {0, 1, 0}, {255, 255, 0, 255}}};
  const float half[3] = {w / 2, h / 2, d / 2};
  const float center[3] = {cx, cy, cz};
  for (const Face& f : faces) {
    const auto base = static_cast<uint32_t>(m.vertexCount());
    const float su[4] = {-1, 1, 1, -1}, sv[4] = {-1, -1, 1, 1};
    for (int k = 0; k < 4; ++k) {
      for (int a = 0; a < 3; ++a) {
        m.positions.push_back(center[a] + (f.n[a] + su[k] * f.u[a] + sv[k] * f.v[a]) * half[a]);
        m.normals.push_back(f.n[a]);
      }
      m.colors.insert(m.colors.end(), f.c.begin(), f.c.end());
    }
    m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
  }
  return m;
}

// 8-bit linear COLOR_0 is coarse in the darks (see glb.h): a round trip moves
// sRGB values below 40 by up to 6 levels, the rest by at most 2.
inline int colorTolerance(int srgb) { return srgb < 40 ? 6 : 2; }

using Tri = std::array<std::array<float, 3>, 3>;

// Triangles as position triples, each rotated to start at its smallest
// vertex (keeping the winding), then sorted: Draco reorders faces and
// vertices, so meshes are compared as triangle sets.
inline std::vector<Tri> triangles(const MeshData& m) {
  std::vector<Tri> out;
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    Tri tri;
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) tri[k][a] = m.positions[m.indices[t * 3 + k] * 3 + a];
    const int first = static_cast<int>(std::min_element(tri.begin(), tri.end()) - tri.begin());
    std::rotate(tri.begin(), tri.begin() + first, tri.end());
    out.push_back(tri);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Every triangle of `a` has a triangle in `b` within `tol` (same winding).
inline void expectSameTriangles(const MeshData& a, const MeshData& b, float tol) {
  ASSERT_EQ(a.triangleCount(), b.triangleCount());
  const auto ta = triangles(a), tb = triangles(b);
  std::vector<bool> used(tb.size(), false);
  for (const Tri& x : ta) {
    bool found = false;
    for (size_t j = 0; j < tb.size() && !found; ++j) {
      if (used[j]) continue;
      for (int rot = 0; rot < 3 && !found; ++rot) {
        bool same = true;
        for (int k = 0; k < 3 && same; ++k)
          for (int c = 0; c < 3 && same; ++c) same = std::fabs(x[k][c] - tb[j][(k + rot) % 3][c]) <= tol;
        if (same) found = used[j] = true;
      }
    }
    EXPECT_TRUE(found) << "triangle (" << x[0][0] << "," << x[0][1] << "," << x[0][2] << ") ... has no match";
  }
}

// For each vertex of `b`, the vertex of `a` at the same position has the
// same normal and colour (within tolerances).
inline void expectSameAttributes(const MeshData& a, const MeshData& b, float pos_tol, float normal_tol) {
  ASSERT_EQ(b.normals.size(), b.positions.size());
  ASSERT_EQ(b.colors.size(), b.vertexCount() * 4);
  for (size_t v = 0; v < b.vertexCount(); ++v) {
    bool found = false;
    for (size_t u = 0; u < a.vertexCount() && !found; ++u) {
      bool same = true;
      for (int c = 0; c < 3 && same; ++c) same = std::fabs(a.positions[u * 3 + c] - b.positions[v * 3 + c]) <= pos_tol;
      for (int c = 0; c < 3 && same; ++c) same = std::fabs(a.normals[u * 3 + c] - b.normals[v * 3 + c]) <= normal_tol;
      if (!same) continue;
      found = true;
      for (int c = 0; c < 4; ++c)
        EXPECT_NEAR(int(a.colors[u * 4 + c]), int(b.colors[v * 4 + c]), c == 3 ? 0 : colorTolerance(a.colors[u * 4 + c]))
            << "vertex " << v << " channel " << c;
    }
    EXPECT_TRUE(found) << "decoded vertex " << v << " matches no source vertex";
  }
}

inline nlohmann::json glbJson(const std::vector<uint8_t>& glb) {
  uint32_t len;
  std::memcpy(&len, glb.data() + 12, 4);
  return nlohmann::json::parse(glb.begin() + 20, glb.begin() + 20 + len);
}

// Builds a GLB from JSON text and a BIN payload (for hand-made test files).
inline std::vector<uint8_t> makeGlb(std::string json, std::vector<uint8_t> bin) {
  while (json.size() % 4) json.push_back(' ');
  while (bin.size() % 4) bin.push_back(0);
  std::vector<uint8_t> out;
  auto u32 = [&](uint32_t v) { out.insert(out.end(), reinterpret_cast<uint8_t*>(&v), reinterpret_cast<uint8_t*>(&v) + 4); };
  const uint32_t total = static_cast<uint32_t>(12 + 8 + json.size() + (bin.empty() ? 0 : 8 + bin.size()));
  u32(0x46546C67);
  u32(2);
  u32(total);
  u32(static_cast<uint32_t>(json.size()));
  u32(0x4E4F534A);
  out.insert(out.end(), json.begin(), json.end());
  if (!bin.empty()) {
    u32(static_cast<uint32_t>(bin.size()));
    u32(0x004E4942);
    out.insert(out.end(), bin.begin(), bin.end());
  }
  return out;
}

}  // namespace blvd::package::glbtest
