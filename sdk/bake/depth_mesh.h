// Textured depth mesh (Sillion, Drettakis, Bodelet 1997, §4.2 "Impostor
// creation"): one captured layer of far geometry (colour + linear depth from a
// cell's vantage point) becomes a small 3D triangle mesh textured with the
// capture, so the far scenery keeps its parallax for as long as the viewer
// stays in the cell.
//
// Steps (S97 §4.2, steps 3-6 of the paper's list):
//   1. external contour(s) of the covered pixels, simplified by Douglas-Peucker;
//   2. lines of large depth discrepancy, extracted by the paper's iterative
//      "largest discrepancy, follow the chain, fit a polyline" loop;
//   3. a regular grid of points inside the contour ("minimal sampling density");
//   4. a constrained Delaunay triangulation of all of it (triangulateSegments);
//   5. every vertex re-projected in 3D with the depth image, texture
//      coordinates = the vertex's image position.
//
// Thread safety: no state; concurrent calls are fine.
// Errors: bad input returns false with a reason in `why`; nothing throws and
// `out` is cleared on failure. Memory: O(width * height) scratch per call.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "bake/triangulate.h"
#include "geo/mesh.h"

namespace blvd::bake {

// Pinhole camera of a capture. Image coordinates are continuous pixels:
// x = 0 at the left edge, y = 0 at the TOP edge, so pixel (u, v) covers
// [u, u+1] x [v, v+1] and has its centre at (u + 0.5, v + 0.5). World axes
// are glTF's (x east, y up, z south). The ray through image point (x, y) is
//   dir = forward + right * ((2x/width - 1) * tan_half_x)
//                 + up    * ((1 - 2y/height) * tan_half_y)
// and the point at view depth z (distance along `forward`, not along the ray)
// is eye + dir * z. forward/right/up are used as given: they should be an
// orthonormal basis for z to be a true distance along the view axis.
struct PinholeCamera {
  glm::dvec3 eye{0.0};
  glm::dvec3 forward{0.0, 0.0, -1.0};
  glm::dvec3 right{1.0, 0.0, 0.0};
  glm::dvec3 up{0.0, 1.0, 0.0};
  double tan_half_x = 1.0;
  double tan_half_y = 1.0;
  int width = 0;
  int height = 0;

  // The ray direction through continuous image point (x, y) (not normalised:
  // its component along `forward` is 1, so eye + ray(x, y) * z is at depth z).
  glm::dvec3 ray(double x, double y) const;
  // Image point of a world point and its view depth; false when behind the eye.
  bool project(const glm::dvec3& world, glm::dvec2& image, double& depth) const;
};

// One captured layer. Pixel p = y * width + x, top row first.
struct CaptureImage {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgba;  // 4 bytes per pixel, or empty (the mesh does not need it)
  // View depth z per pixel in metres; +inf, NaN or <= 0 where nothing was
  // drawn (background). Depths outside [1e-6, 1e15] count as background.
  std::vector<float> depth;
  // Optional: 0 = background or excluded (for example the underside of the
  // ground, drawn in the paper's special colour), non-zero = geometry. Empty:
  // derived from depth. A pixel is covered only when both say so.
  std::vector<uint8_t> mask;
};

struct DepthMeshOptions {
  // Relative depth discrepancy |z_p - z_q| / min(z_p, z_q) between 8-neighbours
  // above which a depth step is cut. Relative, not metres: a step of 1 m is a
  // strong parallax cue at 20 m and noise at 2 km; the parallax a step makes
  // when the eye moves by b is about b * |1/z_p - 1/z_q| = b/z_q * (relative
  // discrepancy), so one threshold means one parallax error at every range.
  double discrepancy_threshold = 0.04;
  // Spacing of the regular grid of points inside the contour, pixels.
  int grid_spacing_px = 24;
  // Douglas-Peucker tolerances (pixels) of the contour and discrepancy lines.
  double contour_tolerance_px = 1.0;
  double line_tolerance_px = 1.0;
  // Discrepancy chains with fewer pixels are dropped.
  int min_chain_px = 4;
  // Measure discrepancy against a first-order prediction: 1/z is affine in
  // image space over a plane, so a neighbour is compared with the value its
  // own side extrapolates. Ground seen at grazing angles then gives no false
  // steps near the horizon, where plain neighbour differences exceed any
  // threshold. false: the paper's plain neighbour difference.
  bool planar_prediction = true;
  // Rounds of refinement: a covered pixel inside a triangle whose plane
  // misses its depth by more than the discrepancy threshold (a crease, such
  // as ground meeting a wall, spanned by one triangle) becomes a vertex and
  // the triangulation is made again, at most this many times. 0: none.
  int refine_rounds = 3;
};

struct DepthMeshStats {
  size_t contours = 0;              // closed contour loops (outer boundaries and holes)
  size_t contour_segments = 0;      // after simplification
  size_t discrepancy_chains = 0;    // kept chains (>= min_chain_px)
  size_t discrepancy_segments = 0;  // after simplification
  size_t grid_points = 0;           // grid points handed to the triangulation
  size_t triangles = 0;             // in `out`
  size_t vertices = 0;              // in `out`
  size_t split_vertices = 0;        // extra copies made where a vertex has two depths
  size_t refine_points = 0;         // vertices added where a triangle missed the surface
  double seconds = 0.0;             // wall time of the call
};

// Optional debug output: the 2D constraints in image coordinates (pixels,
// y down), for tests and the bake report.
struct DepthMeshDebug {
  std::vector<Segment2> contour;      // simplified contour segments
  std::vector<Segment2> discrepancy;  // simplified discrepancy segments
  std::vector<glm::dvec2> grid;       // grid points used
  std::vector<glm::dvec2> image_pos;  // per output vertex: its image position
};

// Builds the textured depth mesh of `img` seen by `cam` into `out`:
// - positions: world, glTF axes (eye + ray(x, y) * z);
// - texcoords: u = x / width, v = y / height of the vertex's image position,
//   top-left origin, which is glTF's convention for an image stored top row
//   first (as `rgba` is): no flip needed;
// - indices: counter-clockwise as seen from the camera (front faces face it);
// - normals and colours are left empty (impostors are drawn unlit: the
//   texture already holds the shading), and so is `image`: the caller
//   compresses `rgba` (the bake module has no image encoder).
// Returns false with a reason for invalid input (size mismatch, bad camera)
// or when nothing is covered. `stats` and `debug` may be null.
bool buildDepthMesh(const CaptureImage& img, const PinholeCamera& cam, const DepthMeshOptions& opt,
                    geo::MeshData& out, DepthMeshStats* stats, std::string& why,
                    DepthMeshDebug* debug = nullptr);

// Triangles of a depth mesh captured from `eye` that stand edge-on to it and
// face a viewer at `viewer` (an end of the run) at least twice as squarely:
// |n . ray| below `max_cos` from the eye (0.2: within 12 degrees of edge-on)
// and more than twice that from the viewer. A triangle the capture saw
// edge-on holds almost no texels and mostly spans a depth step the
// discrepancy lines missed (S97 §4.2: a triangle across a step is a "rubber
// sheet"); from an end of the run it opens into a needle across the near street.
// Horizontal triangles (ground, roofs: |n.y| >= 0.9) are kept: ground is seen
// edge-on from every eye on a street, and stays thin from each. Both points
// in the mesh's frame (glTF axes). Returns the triangles dropped; unused
// vertices stay.
size_t dropEdgeOnTriangles(geo::MeshData& mesh, const glm::dvec3& eye, const glm::dvec3& viewer, double max_cos);

// A skirt under the captured geometry, as terrain LOD hangs one under a
// tile's edges to hide cracks: every covered pixel with background (alpha 0,
// not an underside) below it is continued `rows` pixels straight down at its
// own depth (a vertical curtain), its colour copied. Why: far ground seen
// edge-on is a row or two of pixels at the horizon, and from a viewer ahead
// of the vantage point its near edge drops below where the capture put it;
// without the skirt that row shows the background and the block goes
// missing. The curtain stands at the edge's depth, so the local model in
// front of it (the near ground and streets) still hides it.
// Returns the pixels added. Needs rgba, depth and mask of equal sizes.
size_t hangSkirt(CaptureImage& img, int rows);

}  // namespace blvd::bake
