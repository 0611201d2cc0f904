// Plane extraction: row 3 of the clip matrix plus or minus rows 0..2 gives
// the left/right, bottom/top and near/far planes (GL clip space, -w..w).
// The nearest visible point of a box: its faces clipped by the six planes
// (Sutherland & Hodgman 1974), the nearest point of what remains.
#include "render/frustum.h"

#include <algorithm>
#include <limits>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>

namespace blvd::render {
namespace {

// A box face clipped by up to six planes: each plane adds at most a vertex.
struct Polygon {
  glm::dvec3 p[10];
  int n = 0;
};

double side(const glm::dvec4& pl, const glm::dvec3& p) { return pl.x * p.x + pl.y * p.y + pl.z * p.z + pl.w; }

void clip(Polygon& poly, const glm::dvec4& pl) {
  Polygon out;
  for (int i = 0; i < poly.n; ++i) {
    const glm::dvec3& a = poly.p[i];
    const glm::dvec3& b = poly.p[(i + 1) % poly.n];
    const double da = side(pl, a), db = side(pl, b);
    if (da >= 0) out.p[out.n++] = a;
    if ((da >= 0) != (db >= 0)) out.p[out.n++] = a + (b - a) * (da / (da - db));
  }
  poly = out;
}

double segmentDistance(const glm::dvec3& a, const glm::dvec3& b) {
  const glm::dvec3 ab = b - a;
  const double len2 = glm::dot(ab, ab);
  const double t = len2 > 0 ? std::clamp(-glm::dot(a, ab) / len2, 0.0, 1.0) : 0.0;
  return glm::length(a + ab * t);
}

// The origin's distance to a convex polygon lying in the plane where
// coordinate `axis` is constant.
double polygonDistance(const Polygon& poly, int axis) {
  glm::dvec3 foot(0.0);
  foot[axis] = poly.p[0][axis];
  glm::dvec3 normal(0.0);
  normal[axis] = 1.0;
  bool pos = false, neg = false;
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < poly.n; ++i) {
    const glm::dvec3& a = poly.p[i];
    const glm::dvec3& b = poly.p[(i + 1) % poly.n];
    const double turn = glm::dot(glm::cross(b - a, foot - a), normal);
    (turn >= 0 ? pos : neg) = true;
    best = std::min(best, segmentDistance(a, b));
  }
  return pos && neg ? best : std::abs(foot[axis]);
}

// The corner where the near plane meets two side planes.
glm::dvec3 corner(const glm::dvec4& a, const glm::dvec4& b, const glm::dvec4& c) {
  const glm::dmat3 rows = glm::transpose(glm::dmat3(glm::dvec3(a), glm::dvec3(b), glm::dvec3(c)));
  return glm::inverse(rows) * -glm::dvec3(a.w, b.w, c.w);
}

}  // namespace

Frustum Frustum::fromClip(const glm::dmat4& m) {
  // glm is column-major: m[col][row].
  auto row = [&m](int r) { return glm::dvec4(m[0][r], m[1][r], m[2][r], m[3][r]); };
  const glm::dvec4 r0 = row(0), r1 = row(1), r2 = row(2), r3 = row(3);
  Frustum f{};
  f.planes[0] = r3 + r0;
  f.planes[1] = r3 - r0;
  f.planes[2] = r3 + r1;
  f.planes[3] = r3 - r1;
  f.planes[4] = r3 + r2;
  f.planes[5] = r3 - r2;
  for (int lr = 0; lr < 2; ++lr)
    for (int bt = 2; bt < 4; ++bt)
      f.near_reach = std::max(f.near_reach, glm::length(corner(f.planes[4], f.planes[lr], f.planes[bt])));
  return f;
}

double Frustum::nearestInside(const glm::dvec3& center, const glm::dvec3& half) const {
  const glm::dvec3 lo = center - half, hi = center + half;
  const double box_distance = glm::length(glm::max(glm::max(lo, -hi), glm::dvec3(0.0)));
  if (box_distance <= near_reach) return intersectsBox(center, half) ? box_distance : kOutside;
  double best = kOutside;
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (const double at : {lo[axis], hi[axis]}) {
      Polygon face;
      face.n = 4;
      for (int k = 0; k < 4; ++k) {
        glm::dvec3& p = face.p[k];
        p[axis] = at;
        p[u] = (k == 1 || k == 2) ? hi[u] : lo[u];
        p[v] = (k >= 2) ? hi[v] : lo[v];
      }
      for (const glm::dvec4& pl : planes)
        if (face.n) clip(face, pl);
      if (face.n >= 3) best = std::min(best, polygonDistance(face, axis));
    }
  }
  return best;
}

}  // namespace blvd::render
