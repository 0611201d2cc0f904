// Test scenes for the render tests: boxes and flat ribbons as MeshData in
// glTF axes (x = east, y = up, z = south), plus pixel helpers.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "geo/mesh.h"

namespace blvd::render::test {

// Axis-aligned box, 24 vertices with per-face normals, counter-clockwise
// seen from outside. `center` and `size` in glTF axes.
inline geo::MeshData makeBox(float cx, float cy, float cz, float sx, float sy, float sz,
                             const uint8_t rgba[4]) {
  geo::MeshData m;
  const float hx = sx / 2, hy = sy / 2, hz = sz / 2;
  // Each face: normal, then its four corners counter-clockwise from outside.
  struct Face {
    float n[3];
    float c[4][3];
  };
  const Face faces[6] = {
      {{1, 0, 0}, {{1, -1, 1}, {1, -1, -1}, {1, 1, -1}, {1, 1, 1}}},
      {{-1, 0, 0}, {{-1, -1, -1}, {-1, -1, 1}, {-1, 1, 1}, {-1, 1, -1}}},
      {{0, 1, 0}, {{-1, 1, 1}, {1, 1, 1}, {1, 1, -1}, {-1, 1, -1}}},
      {{0, -1, 0}, {{-1, -1, -1}, {1, -1, -1}, {1, -1, 1}, {-1, -1, 1}}},
      {{0, 0, 1}, {{-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}}},
      {{0, 0, -1}, {{1, -1, -1}, {-1, -1, -1}, {-1, 1, -1}, {1, 1, -1}}},
  };
  for (const Face& f : faces) {
    const auto base = static_cast<uint32_t>(m.vertexCount());
    for (const auto& c : f.c) {
      m.positions.insert(m.positions.end(), {cx + c[0] * hx, cy + c[1] * hy, cz + c[2] * hz});
      m.normals.insert(m.normals.end(), {f.n[0], f.n[1], f.n[2]});
      m.colors.insert(m.colors.end(), {rgba[0], rgba[1], rgba[2], rgba[3]});
    }
    m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
  }
  return m;
}

// Flat quad at height y from (x0, z0) to (x1, z1), facing up; no normals, so
// the renderer computes them.
inline geo::MeshData makeFlat(float x0, float z0, float x1, float z1, float y,
                              const uint8_t rgba[4]) {
  geo::MeshData m;
  m.positions = {x0, y, z1, x1, y, z1, x1, y, z0, x0, y, z0};
  for (int i = 0; i < 4; ++i) m.colors.insert(m.colors.end(), {rgba[0], rgba[1], rgba[2], rgba[3]});
  m.indices = {0, 1, 2, 0, 2, 3};
  return m;
}

struct Rgb {
  int r, g, b;
};

inline Rgb pixel(const std::vector<uint8_t>& img, int w, int x, int y) {
  const size_t i = (static_cast<size_t>(y) * w + x) * 4;
  return {img[i], img[i + 1], img[i + 2]};
}

// Where test images go, for a human to look at.
inline std::string outPath(const std::string& name) {
  return std::string(BLVD_BINARY_DIR) + "/tests/render/" + name;
}

}  // namespace blvd::render::test
