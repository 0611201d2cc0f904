// Plane extraction: row 3 of the clip matrix plus or minus rows 0..2 gives
// the left/right, bottom/top and near/far planes (GL clip space, -w..w).
#include "render/frustum.h"

namespace blvd::render {

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
  return f;
}

}  // namespace blvd::render
