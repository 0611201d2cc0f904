// The street-level camera and its matrices. Matrices stay in double on the
// CPU and are camera-relative: the eye is the origin, so a city tens of
// kilometres across keeps millimetre precision once converted to float for GL.
//
// World axes are glTF's (geo/mesh.h): x = east, y = up, z = south.
#pragma once
#include <glm/glm.hpp>

namespace blvd::render {

struct Camera {
  glm::dvec3 eye_enu{0.0, 0.0, 1.5};  // metres east, north, up in the package frame
  double heading_deg = 0.0;           // clockwise from north
  double pitch_deg = 0.0;             // up positive, within (-90, 90)
  double fov_y_deg = 45.0;            // vertical field of view, within (0, 180)
  double near_m = 0.5;
  double far_m = 3000.0;
  int width = 800;  // viewport in pixels; also sets the aspect ratio
  int height = 480;
  int viewport_x = 0;  // viewport's lower-left corner in the framebuffer (GL convention)
  int viewport_y = 0;
  bool mirror = false;  // left-right flipped, as a rear-view mirror shows the road
};

// nullptr when usable, else static text naming the bad field.
const char* validateCamera(const Camera& cam);

// (east, north, up) -> glTF (x = east, y = up, z = south).
inline glm::dvec3 enuToGltf(const glm::dvec3& enu) { return {enu.x, enu.z, -enu.y}; }

// Unit view direction in glTF axes.
glm::dvec3 viewForward(const Camera& cam);

// World-to-view rotation (no translation: positions are eye-relative).
glm::dmat4 viewRotation(const Camera& cam);

// OpenGL clip space, depth in [-1, 1].
glm::dmat4 projection(const Camera& cam);

// projection * viewRotation: maps eye-relative glTF positions to clip space.
glm::dmat4 viewProjectionRelative(const Camera& cam);

}  // namespace blvd::render
