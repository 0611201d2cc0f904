// Building extrusion (see extrude.h).
//
// Walls are built from Triangulation::boundary, the outline of the triangles
// triangulate() kept, rather than from the input rings. The outline is already
// oriented (solid on the left) whatever the rings' winding, skips the edges
// two touching holes share, and agrees with the roof for self-touching or
// self-intersecting rings, where orienting each ring by its signed area
// would not.
#include "bake/extrude.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "bake/plane_geometry.h"

namespace blvd::bake {
namespace {

// Outline vertices that stray less than this from a straight wall are merged
// into it. OSM places a node wherever a neighbouring building touches the
// wall, so straight facades often carry several; merging keeps two triangles
// per visible wall. The roof still has those vertices, so the merge opens a
// gap of at most this size under the roof edge: 1 mm is invisible.
constexpr double kWallMergeTolerance = 1e-3;  // metres

// Shorter outline edges get no wall: a normal from such an edge is noise.
constexpr double kMinWallLength = 1e-6;  // metres

struct Builder {
  geo::MeshData mesh;
  const uint8_t* wall_rgba;
  const uint8_t* roof_rgba;

  uint32_t vertex(double e, double n, double u, glm::dvec3 normal_enu, const uint8_t rgba[4]) {
    float p[3], nn[3];
    geo::enuToGltf(e, n, u, p);
    geo::enuToGltf(normal_enu.x, normal_enu.y, normal_enu.z, nn);
    mesh.positions.insert(mesh.positions.end(), p, p + 3);
    mesh.normals.insert(mesh.normals.end(), nn, nn + 3);
    mesh.colors.insert(mesh.colors.end(), rgba, rgba + 4);
    return static_cast<uint32_t>(mesh.vertexCount() - 1);
  }

  // Quad from a to b with the solid on the left, so it faces right (outward).
  void wall(glm::dvec2 a, glm::dvec2 b, double lo, double hi) {
    const glm::dvec2 d = b - a;
    const double len = glm::length(d);
    if (!(len >= kMinWallLength)) return;
    const glm::dvec3 n(d.y / len, -d.x / len, 0.0);
    const uint32_t i0 = vertex(a.x, a.y, lo, n, wall_rgba);
    const uint32_t i1 = vertex(b.x, b.y, lo, n, wall_rgba);
    const uint32_t i2 = vertex(b.x, b.y, hi, n, wall_rgba);
    const uint32_t i3 = vertex(a.x, a.y, hi, n, wall_rgba);
    // Seen from outside, a is bottom-left and b bottom-right.
    mesh.indices.insert(mesh.indices.end(), {i0, i1, i2, i0, i2, i3});
  }

  // Horizontal copy of the triangulation at height u; facing down flips the
  // winding so it stays counter-clockwise seen from below.
  void cap(const Triangulation& t, double u, bool up, const uint8_t rgba[4]) {
    const uint32_t base = static_cast<uint32_t>(mesh.vertexCount());
    const glm::dvec3 n(0.0, 0.0, up ? 1.0 : -1.0);
    for (const glm::dvec2& v : t.vertices) vertex(v.x, v.y, u, n, rgba);
    for (size_t i = 0; i + 2 < t.indices.size(); i += 3) {
      const uint32_t a = base + t.indices[i];
      const uint32_t b = base + t.indices[i + 1];
      const uint32_t c = base + t.indices[i + 2];
      if (up) {
        mesh.indices.insert(mesh.indices.end(), {a, b, c});
      } else {
        mesh.indices.insert(mesh.indices.end(), {a, c, b});
      }
    }
  }

  // Emits walls along a chain of outline vertices, greedily merging runs
  // whose inner vertices all lie within kWallMergeTolerance of the wall.
  void chain(const std::vector<glm::dvec2>& v, const std::vector<uint32_t>& c, double lo,
             double hi) {
    size_t i = 0;
    while (i + 1 < c.size()) {
      size_t j = i + 1;
      while (j + 1 < c.size()) {
        bool straight = true;
        for (size_t m = i + 1; m <= j && straight; ++m) {
          straight = pointSegmentDistance(v[c[m]], v[c[i]], v[c[j + 1]]) < kWallMergeTolerance;
        }
        if (!straight) break;
        ++j;
      }
      wall(v[c[i]], v[c[j]], lo, hi);
      i = j;
    }
  }

  // Splits the outline into chains between "corners" (vertices where the
  // outline branches, as at a self-touching point, or bends) and walls them.
  void walls(const Triangulation& t, double lo, double hi) {
    const std::vector<glm::dvec2>& v = t.vertices;
    const size_t edges = t.boundary.size() / 2;
    constexpr size_t kNone = std::numeric_limits<size_t>::max();
    std::vector<int> in(v.size(), 0), out(v.size(), 0);
    std::vector<size_t> next(v.size(), kNone), prev(v.size(), kNone);
    for (size_t e = 0; e < edges; ++e) {
      const uint32_t a = t.boundary[2 * e], b = t.boundary[2 * e + 1];
      ++out[a];
      ++in[b];
      next[a] = e;
      prev[b] = e;
    }
    std::vector<bool> corner(v.size(), true);
    for (size_t k = 0; k < v.size(); ++k) {
      if (in[k] != 1 || out[k] != 1) continue;
      const glm::dvec2 a = v[t.boundary[2 * prev[k]]];
      const glm::dvec2 b = v[t.boundary[2 * next[k] + 1]];
      corner[k] = !(pointSegmentDistance(v[k], a, b) < kWallMergeTolerance);
    }
    std::vector<bool> used(edges, false);
    std::vector<uint32_t> c;
    // Follows unique successors from edge e until a corner (or back to the
    // start on a loop without corners).
    auto walk = [&](size_t e) {
      c.assign({t.boundary[2 * e]});
      while (e != kNone && !used[e]) {
        used[e] = true;
        const uint32_t b = t.boundary[2 * e + 1];
        c.push_back(b);
        if (corner[b]) break;
        e = next[b];
      }
      chain(v, c, lo, hi);
    };
    for (size_t e = 0; e < edges; ++e) {
      if (!used[e] && corner[t.boundary[2 * e]]) walk(e);
    }
    for (size_t e = 0; e < edges; ++e) {  // smooth loops, e.g. a round tower
      if (!used[e]) walk(e);
    }
  }
};

// SplitMix64's output function (Steele, Lea, Flood, "Fast Splittable
// Pseudorandom Number Generators", OOPSLA 2014): consecutive OSM ids map to
// unrelated bits, so neighbouring buildings differ.
uint64_t mix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

}  // namespace

bool extrudeBuilding(const Polygon2& footprint, double min_height, double height,
                     const uint8_t wall_rgba[4], const uint8_t roof_rgba[4],
                     geo::MeshData& out, std::string& why) {
  why.clear();
  if (!std::isfinite(min_height) || !std::isfinite(height)) {
    why = "height is not finite";
    return false;
  }
  if (!(height > min_height)) {
    why = "height must exceed min_height";
    return false;
  }
  if (wall_rgba == nullptr || roof_rgba == nullptr) {
    why = "no colour";
    return false;
  }
  Triangulation t;
  if (!triangulate(footprint, t, why)) return false;

  const size_t old_positions = out.positions.size(), old_normals = out.normals.size(),
               old_colors = out.colors.size(), old_indices = out.indices.size();
  try {
    Builder b{{}, wall_rgba, roof_rgba};
    b.walls(t, min_height, height);
    b.cap(t, height, true, roof_rgba);
    if (min_height > 0.0) b.cap(t, min_height, false, wall_rgba);
    if (out.vertexCount() + b.mesh.vertexCount() > std::numeric_limits<uint32_t>::max()) {
      why = "mesh would exceed 32-bit vertex indices";
      return false;
    }
    out.append(b.mesh);
  } catch (const std::exception& e) {  // std::bad_alloc: leave `out` as it was
    out.positions.resize(old_positions);
    out.normals.resize(old_normals);
    out.colors.resize(old_colors);
    out.indices.resize(old_indices);
    why = std::string("extrusion failed: ") + e.what();
    return false;
  }
  return true;
}

void buildingColour(uint64_t osm_id, uint8_t rgba[4]) {
  // Plastered facades of the Riviera: cream and white dominate, the warmer
  // ochre and salmon less so; repeats weight the draw.
  static const uint8_t kPalette[][3] = {
      {0xF2, 0xE6, 0xCC},  // cream
      {0xEF, 0xE1, 0xC2},  // cream, warmer
      {0xF5, 0xF3, 0xEC},  // white
      {0xF8, 0xF6, 0xF1},  // white, cooler
      {0xDC, 0xAE, 0x66},  // ochre
      {0xE6, 0xC0, 0x7E},  // light ochre
      {0xE8, 0xA8, 0x8E},  // salmon
      {0xF0, 0xC0, 0xA8},  // light salmon
      {0xD2, 0xD0, 0xCB},  // light grey
  };
  constexpr uint64_t kCount = sizeof(kPalette) / sizeof(kPalette[0]);
  const uint64_t h = mix(osm_id);
  const uint8_t* base = kPalette[h % kCount];
  // Brightness 0.92 .. 1.04 from bits the palette pick did not use.
  const double f = 0.92 + 0.12 * static_cast<double>((h >> 32) & 0xFFFF) / 65535.0;
  for (int i = 0; i < 3; ++i) {
    rgba[i] = static_cast<uint8_t>(std::clamp(std::lround(base[i] * f), 0L, 255L));
  }
  rgba[3] = 255;
}

void roofColour(const uint8_t wall_rgba[4], uint8_t roof_rgba[4]) {
  for (int i = 0; i < 3; ++i) roof_rgba[i] = static_cast<uint8_t>(wall_rgba[i] * 0.82 + 0.5);
  roof_rgba[3] = wall_rgba[3];
}

}  // namespace blvd::bake
