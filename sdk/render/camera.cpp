// Camera matrices. A camera at heading h and pitch p looks along
// (sin h cos p, sin p, -cos h cos p) in glTF axes: heading turns clockwise
// seen from above, i.e. a negative rotation about +y, applied after pitch.
#include "render/camera.h"

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>

namespace blvd::render {

const char* validateCamera(const Camera& cam) {
  if (!std::isfinite(cam.eye_enu.x) || !std::isfinite(cam.eye_enu.y) ||
      !std::isfinite(cam.eye_enu.z)) {
    return "camera eye is not finite";
  }
  if (!std::isfinite(cam.heading_deg)) return "camera heading is not finite";
  if (!(cam.pitch_deg > -90.0 && cam.pitch_deg < 90.0)) return "camera pitch outside (-90, 90)";
  if (!(cam.fov_y_deg > 0.0 && cam.fov_y_deg < 180.0)) return "camera fov_y outside (0, 180)";
  if (!(cam.near_m > 0.0) || !std::isfinite(cam.near_m)) return "camera near must be > 0";
  if (!(cam.far_m > cam.near_m) || !std::isfinite(cam.far_m)) return "camera far must be > near";
  if (cam.width <= 0 || cam.height <= 0) return "camera width and height must be > 0";
  return nullptr;
}

glm::dvec3 viewForward(const Camera& cam) {
  const double h = glm::radians(cam.heading_deg);
  const double p = glm::radians(cam.pitch_deg);
  return {std::sin(h) * std::cos(p), std::sin(p), -std::cos(h) * std::cos(p)};
}

glm::dmat4 viewRotation(const Camera& cam) {
  // Camera-to-world is Ry(-h) * Rx(p); the view matrix is its inverse.
  const glm::dmat4 identity(1.0);
  const glm::dmat4 unpitch = glm::rotate(identity, -glm::radians(cam.pitch_deg), {1.0, 0.0, 0.0});
  return glm::rotate(unpitch, glm::radians(cam.heading_deg), {0.0, 1.0, 0.0});
}

glm::dmat4 projection(const Camera& cam) {
  if (cam.mirror) {
    Camera plain = cam;
    plain.mirror = false;
    return glm::scale(glm::dmat4(1.0), glm::dvec3(-1.0, 1.0, 1.0)) * projection(plain);
  }
  const double aspect = static_cast<double>(cam.width) / static_cast<double>(cam.height);
  return glm::perspective(glm::radians(cam.fov_y_deg), aspect, cam.near_m, cam.far_m);
}

glm::dmat4 viewProjectionRelative(const Camera& cam) {
  return projection(cam) * viewRotation(cam);
}

}  // namespace blvd::render
