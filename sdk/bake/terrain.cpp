#include "bake/terrain.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <unordered_map>
#include <unordered_set>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "core/status.h"

namespace blvd::bake {

namespace {

glm::dvec2 horizontal(const geo::MeshData& m, uint32_t v) {
  return {m.positions[3 * size_t(v)], -double(m.positions[3 * size_t(v) + 2])};  // east, north
}

// The midpoint of edge (a, b), made once and shared by both its triangles.
uint32_t midpoint(geo::MeshData& m, uint32_t a, uint32_t b, std::unordered_map<uint64_t, uint32_t>& made) {
  const uint64_t key = (uint64_t(std::min(a, b)) << 32) | std::max(a, b);
  if (auto it = made.find(key); it != made.end()) return it->second;
  const auto v = static_cast<uint32_t>(m.vertexCount());
  for (int k = 0; k < 3; ++k) m.positions.push_back(0.5f * (m.positions[3 * size_t(a) + k] + m.positions[3 * size_t(b) + k]));
  if (!m.normals.empty())
    for (int k = 0; k < 3; ++k) m.normals.push_back(0.5f * (m.normals[3 * size_t(a) + k] + m.normals[3 * size_t(b) + k]));
  if (!m.colors.empty())
    for (int k = 0; k < 4; ++k)
      m.colors.push_back(uint8_t((unsigned(m.colors[4 * size_t(a) + k]) + m.colors[4 * size_t(b) + k] + 1) / 2));
  if (!m.texcoords.empty())
    for (int k = 0; k < 2; ++k)
      m.texcoords.push_back(0.5f * (m.texcoords[2 * size_t(a) + k] + m.texcoords[2 * size_t(b) + k]));
  made.emplace(key, v);
  return v;
}

}  // namespace

TerrainHeight demHeights(const Dem& dem, const geo::LocalFrame& frame) {
  return [&dem, frame](glm::dvec2 en) {
    double lat, lon, h;
    frame.reverse(geo::Enu{en.x, en.y, 0}, lat, lon, h);
    return dem.height(lat, lon) - frame.h0();  // NaN stays NaN
  };
}

TerrainHeight demTerrain(const Dem& dem, const geo::LocalFrame& frame) {
  return [heights = demHeights(dem, frame), frame](glm::dvec2 en) {
    const double z = heights(en);
    if (std::isnan(z)) {
      double lat, lon, h;
      frame.reverse(geo::Enu{en.x, en.y, 0}, lat, lon, h);
      char buf[128];
      std::snprintf(buf, sizeof buf, "terrain: no DEM height at %.6f, %.6f (east %.1f m, north %.1f m)", lat, lon,
                    en.x, en.y);
      throw core::Error(core::Status::Internal, buf);
    }
    return z;
  };
}

namespace {

uint64_t edgeKey(uint32_t a, uint32_t b) { return (uint64_t(std::min(a, b)) << 32) | std::max(a, b); }

// Rivara's longest-edge bisection: the edges `split(a, b, l2)` asks for are
// marked; a triangle with a marked edge has its longest edge marked too
// (repeated until nothing changes), and is bisected along its longest edge,
// its halves again while they hold a marked edge. Splitting only longest
// edges keeps the triangles' angles bounded (no slivers). Every edge is split
// at one shared midpoint, and the next round marks any edge whose midpoint a
// neighbour made, so no vertex is left inside an edge when the rounds end
// (when no edge is marked).
template <class Split>
void bisect(geo::MeshData& m, const Split& split) {
  std::unordered_map<uint64_t, uint32_t> made;
  auto len2 = [&](uint32_t a, uint32_t b) {
    const glm::dvec2 d = horizontal(m, b) - horizontal(m, a);
    return glm::dot(d, d);
  };
  auto longest = [&](const uint32_t* v) {
    int e = 0;
    for (int k = 1; k < 3; ++k)
      if (len2(v[k], v[(k + 1) % 3]) > len2(v[e], v[(e + 1) % 3])) e = k;
    return e;
  };
  for (;;) {
    std::unordered_set<uint64_t> marked;
    for (size_t t = 0; t + 2 < m.indices.size(); t += 3)
      for (int k = 0; k < 3; ++k) {
        const uint32_t a = m.indices[t + k], b = m.indices[t + (k + 1) % 3];
        // An edge a neighbour already split (its midpoint exists) is split
        // here too: no vertex stays inside an edge.
        if (made.count(edgeKey(a, b)) || split(a, b, len2(a, b))) marked.insert(edgeKey(a, b));
      }
    if (marked.empty()) return;
    for (bool grew = true; grew;) {  // the closure: a marked triangle's longest edge is marked
      grew = false;
      for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
        const uint32_t* v = &m.indices[t];
        bool any = false;
        for (int k = 0; k < 3; ++k) any |= marked.count(edgeKey(v[k], v[(k + 1) % 3])) > 0;
        const int e = longest(v);
        if (any && marked.insert(edgeKey(v[e], v[(e + 1) % 3])).second) grew = true;
      }
    }
    std::vector<uint32_t> work = std::move(m.indices), done;
    m.indices.clear();
    while (!work.empty()) {
      const uint32_t v[3] = {work[work.size() - 3], work[work.size() - 2], work[work.size() - 1]};
      work.resize(work.size() - 3);
      bool any = false;
      for (int k = 0; k < 3; ++k) any |= marked.count(edgeKey(v[k], v[(k + 1) % 3])) > 0;
      if (!any) {
        done.insert(done.end(), v, v + 3);
        continue;
      }
      const int e = longest(v);
      const uint32_t a = v[e], b = v[(e + 1) % 3], c = v[(e + 2) % 3];
      marked.insert(edgeKey(a, b));  // split along its longest edge: marked, for the triangle across it
      const uint32_t mid = midpoint(m, a, b, made);
      work.insert(work.end(), {a, mid, c, mid, b, c});  // the winding kept
    }
    m.indices = std::move(done);
  }
}
}  // namespace

void subdivideLongEdges(geo::MeshData& m, double max_edge_m) {
  const double limit2 = max_edge_m * max_edge_m;
  bisect(m, [&](uint32_t, uint32_t, double l2) { return l2 > limit2; });
}

void subdivideForTerrain(geo::MeshData& m, const TerrainHeight& terrain, const DrapeTolerance& tol) {
  const double max2 = tol.max_edge_m * tol.max_edge_m, min2 = tol.min_edge_m * tol.min_edge_m;
  bisect(m, [&](uint32_t a, uint32_t b, double l2) {
    if (l2 > max2) return true;
    if (l2 <= min2) return false;
    const glm::dvec2 pa = horizontal(m, a), pb = horizontal(m, b);
    return std::abs(terrain(0.5 * (pa + pb)) - 0.5 * (terrain(pa) + terrain(pb))) > tol.height_m;
  });
}

void drapeOnTerrain(geo::MeshData& m, const TerrainHeight& terrain) {
  const size_t n = m.vertexCount();
  for (size_t v = 0; v < n; ++v) m.positions[3 * v + 1] += float(terrain(horizontal(m, uint32_t(v))));
  std::vector<glm::dvec3> acc(n, glm::dvec3(0));
  auto at = [&](uint32_t v) { return glm::dvec3(m.positions[3 * size_t(v)], m.positions[3 * size_t(v) + 1], m.positions[3 * size_t(v) + 2]); };
  for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
    const uint32_t a = m.indices[t], b = m.indices[t + 1], c = m.indices[t + 2];
    const glm::dvec3 nrm = glm::cross(at(b) - at(a), at(c) - at(a));  // area-weighted
    acc[a] += nrm, acc[b] += nrm, acc[c] += nrm;
  }
  m.normals.resize(3 * n);
  for (size_t v = 0; v < n; ++v) {
    const double l = glm::length(acc[v]);
    const glm::dvec3 u = l > 0 ? acc[v] / l : glm::dvec3(0, 1, 0);
    for (int k = 0; k < 3; ++k) m.normals[3 * v + k] = float(u[k]);
  }
}

void raiseBySlope(geo::MeshData& m, const TerrainHeight& terrain, double per_slope_m, double max_m) {
  constexpr double d = 1.0;  // metres either side: central differences
  for (size_t v = 0; v < m.vertexCount(); ++v) {
    const glm::dvec2 p = horizontal(m, uint32_t(v));
    const double gx = (terrain(p + glm::dvec2(d, 0)) - terrain(p - glm::dvec2(d, 0))) / (2 * d);
    const double gy = (terrain(p + glm::dvec2(0, d)) - terrain(p - glm::dvec2(0, d))) / (2 * d);
    m.positions[3 * v + 1] += float(std::min(max_m, per_slope_m * std::sqrt(gx * gx + gy * gy)));
  }
}

void raise(geo::MeshData& m, double dy) {
  for (size_t v = 0; v < m.vertexCount(); ++v) m.positions[3 * v + 1] += float(dy);
}

namespace {
// Even-odd point in polygon over every ring (outer and inner).
bool inside(const Polygon2& poly, glm::dvec2 p) {
  bool in = false;
  auto ring = [&](const Ring& r) {
    const size_t n = r.pts.size();
    for (size_t i = 0, j = n - 1; i < n; j = i++) {
      const glm::dvec2 a = r.pts[i], b = r.pts[j];
      if ((a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x) in = !in;
    }
  };
  if (!poly.outer.pts.empty()) ring(poly.outer);
  for (const Ring& r : poly.inners)
    if (!r.pts.empty()) ring(r);
  return in;
}
}  // namespace

double lowestUnder(const std::vector<Polygon2>& footprint, const TerrainHeight& terrain, double step_m) {
  double low = std::numeric_limits<double>::infinity();
  for (const Polygon2& poly : footprint) {
    glm::dvec2 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
    for (const glm::dvec2& p : poly.outer.pts) {
      low = std::min(low, terrain(p));
      lo = glm::min(lo, p), hi = glm::max(hi, p);
    }
    if (!(step_m > 0) || lo.x > hi.x) continue;
    for (double y = lo.y + 0.5 * step_m; y < hi.y; y += step_m)
      for (double x = lo.x + 0.5 * step_m; x < hi.x; x += step_m)
        if (inside(poly, {x, y})) low = std::min(low, terrain({x, y}));
  }
  return std::isfinite(low) ? low : 0.0;
}

}  // namespace blvd::bake
