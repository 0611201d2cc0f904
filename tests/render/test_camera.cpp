// Camera matrices and frustum culling, without GL.
#include <gtest/gtest.h>

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

}  // namespace
}  // namespace blvd::render
