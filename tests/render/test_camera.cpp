// Camera matrices and frustum culling, without GL.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "render/camera.h"
#include "render/frustum.h"

namespace blvd::render {
namespace {

glm::dvec3 toView(const Camera& cam, const glm::dvec3& world_rel) {
  return glm::dvec3(viewRotation(cam) * glm::dvec4(world_rel, 1.0));
}

TEST(Camera, HeadingIsClockwiseFromNorth) {
  Camera cam;
  // North is -z in glTF; at heading 0 it is straight ahead (view -z).
  glm::dvec3 v = toView(cam, {0, 0, -1});
  EXPECT_NEAR(v.z, -1.0, 1e-12);
  cam.heading_deg = 90.0;  // east
  EXPECT_NEAR(viewForward(cam).x, 1.0, 1e-12);
  v = toView(cam, {1, 0, 0});
  EXPECT_NEAR(v.z, -1.0, 1e-12);
  // North is then on the left.
  v = toView(cam, {0, 0, -1});
  EXPECT_NEAR(v.x, -1.0, 1e-12);
}

TEST(Camera, PitchUpLooksUp) {
  Camera cam;
  cam.heading_deg = 30.0;
  cam.pitch_deg = 20.0;
  const glm::dvec3 f = viewForward(cam);
  EXPECT_GT(f.y, 0.0);
  const glm::dvec3 v = toView(cam, f);
  EXPECT_NEAR(v.x, 0.0, 1e-12);
  EXPECT_NEAR(v.y, 0.0, 1e-12);
  EXPECT_NEAR(v.z, -1.0, 1e-12);
}

TEST(Camera, EnuToGltf) {
  const glm::dvec3 g = enuToGltf({10.0, 20.0, 3.0});
  EXPECT_EQ(g, glm::dvec3(10.0, 3.0, -20.0));
}

TEST(Camera, Validation) {
  Camera cam;
  EXPECT_EQ(validateCamera(cam), nullptr);
  cam.pitch_deg = 90.0;
  EXPECT_NE(validateCamera(cam), nullptr);
  cam = Camera{};
  cam.far_m = cam.near_m;
  EXPECT_NE(validateCamera(cam), nullptr);
  cam = Camera{};
  cam.width = 0;
  EXPECT_NE(validateCamera(cam), nullptr);
  cam = Camera{};
  cam.eye_enu.x = std::nan("");
  EXPECT_NE(validateCamera(cam), nullptr);
}

TEST(Frustum, CullsBehindBesideAndBeyond) {
  Camera cam;  // looking north from the origin, 45 degrees, far 3000
  const Frustum f = Frustum::fromClip(viewProjectionRelative(cam));
  const glm::dvec3 half(2.0);
  EXPECT_TRUE(f.intersectsBox({0, 0, -20}, half));     // ahead
  EXPECT_FALSE(f.intersectsBox({0, 0, 20}, half));     // behind
  EXPECT_FALSE(f.intersectsBox({200, 0, -20}, half));  // far to the right
  EXPECT_FALSE(f.intersectsBox({0, 0, -3100}, half));  // beyond far
  EXPECT_TRUE(f.intersectsBox({0, 0, -2999}, half));   // straddles far
  EXPECT_TRUE(f.intersectsBox({0, 0, 0}, half));       // contains the eye
}

// The nearest point of a box in view, by brute force: a grid over the box,
// its points within `slack` metres of the frustum counted in.
double sampledNearestInside(const Frustum& f, const glm::dvec3& c, const glm::dvec3& h, int n, double slack = 0) {
  double best = Frustum::kOutside;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j)
      for (int k = 0; k <= n; ++k) {
        const glm::dvec3 p = c - h + 2.0 * h * glm::dvec3(i, j, k) / double(n);
        bool in = true;
        for (const glm::dvec4& pl : f.planes)
          in = in && pl.x * p.x + pl.y * p.y + pl.z * p.z + pl.w >= -slack * glm::length(glm::dvec3(pl));
        if (in) best = std::min(best, glm::length(p));
      }
  return best;
}

TEST(Frustum, NearestPointInViewOfABlockBesideTheStreet) {
  Camera cam;  // looking north (-z) from the origin, 45 degrees, 800x480
  const Frustum f = Frustum::fromClip(viewProjectionRelative(cam));
  EXPECT_GT(f.near_reach, cam.near_m);
  EXPECT_LT(f.near_reach, 2 * cam.near_m);
  // A facade 6 m to the right, from 20 m behind to 60 m ahead: its nearest
  // point is beside the car, 6 m away; the nearest it shows is where the
  // frustum's right side meets it, 6 / tan(half the horizontal angle) ahead.
  const glm::dvec3 c(10, 5, -20), h(4, 5, 40);
  const double half_h = std::atan(std::tan(22.5 * 3.14159265358979 / 180) * 800.0 / 480.0);
  const double ahead = 6.0 / std::tan(half_h);
  const double d = f.nearestInside(c, h);
  EXPECT_NEAR(d, std::sqrt(ahead * ahead + 36.0), 1e-6);
  EXPECT_GT(d, 1.5 * 6.0);
  EXPECT_NEAR(d, sampledNearestInside(f, c, h, 80), 1.0);
}

TEST(Frustum, NearestPointInViewAgreesWithSampling) {
  Camera cam;
  cam.heading_deg = 30;
  cam.pitch_deg = 5;
  const Frustum f = Frustum::fromClip(viewProjectionRelative(cam));
  uint32_t seed = 7;
  auto next = [&seed](double lo, double hi) {
    seed = seed * 1664525u + 1013904223u;
    return lo + (hi - lo) * double(seed >> 8) / double(1u << 24);
  };
  int seen = 0, unseen = 0;
  for (int t = 0; t < 200; ++t) {
    const glm::dvec3 c(next(-60, 60), next(-5, 20), next(-60, 60)), h(next(0.5, 20), next(0.5, 15), next(0.5, 20));
    const double cell = glm::length(2.0 * h / 24.0);
    const double exact = f.nearestInside(c, h), sampled = sampledNearestInside(f, c, h, 24);
    // Every point in view is within a grid cell of a grid point within a
    // cell of the frustum: the exact answer is at most a cell nearer.
    const double relaxed = sampledNearestInside(f, c, h, 24, cell);
    if (sampled == Frustum::kOutside) {
      ++unseen;  // the grid can miss a sliver of the box in view; never the other way round
      EXPECT_TRUE(exact == Frustum::kOutside || f.intersectsBox(c, h)) << t;
      continue;
    }
    ++seen;
    EXPECT_LE(exact, sampled + 1e-9) << t;
    EXPECT_GE(exact, relaxed - cell) << t;
  }
  EXPECT_GT(seen, 20);
  EXPECT_GT(unseen, 20);
  EXPECT_EQ(f.nearestInside({0, 0, 30}, glm::dvec3(2.0)), Frustum::kOutside);  // behind
  EXPECT_EQ(f.nearestInside({0, 0, 0}, glm::dvec3(2.0)), 0.0);                // holds the eye
}

}  // namespace
}  // namespace blvd::render
