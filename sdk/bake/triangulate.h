// Polygon triangulation for bake: building footprints (rings with holes) and
// street-block ground polygons (arbitrary constraint segments).
//
// OSM rings are often dirty: repeated nodes, collinear nodes on edges, rings
// that touch themselves, holes that touch each other or the outer ring, and
// the odd self-intersecting "bow-tie". Ear clipping needs a clean simple
// polygon, so both functions build a CGAL constrained Delaunay triangulation
// instead (intersections between constraints are split at computed points)
// and then decide per triangle whether it is inside.
//
// Coordinates are local metres, x = east, y = north. Output triangles are
// counter-clockwise (positive area) in that frame.
//
// Thread safety: the functions keep no state; concurrent calls are fine.
// Errors: bad input returns false with a reason in `why`; nothing throws
// (CGAL's own exceptions are caught) and `out` is cleared on failure.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <glm/vec2.hpp>

namespace blvd::bake {

// A closed ring: the last point connects back to the first. Either winding;
// a repeated closing point (OSM style, first == last) is allowed.
struct Ring {
  std::vector<glm::dvec2> pts;
};

struct Polygon2 {
  Ring outer;
  std::vector<Ring> inners;
};

struct Triangulation {
  std::vector<glm::dvec2> vertices;
  std::vector<uint32_t> indices;   // triangles, counter-clockwise
  // Directed edges (pairs of vertex indices a, b) between a kept triangle and
  // a dropped one or the outside, oriented so the kept region lies on the
  // left. These are the footprint's outline after the inside test, so walls
  // built from them agree with the roof even for self-touching or
  // intersecting input rings.
  std::vector<uint32_t> boundary;

  size_t triangleCount() const { return indices.size() / 3; }
  void clear() {
    vertices.clear();
    indices.clear();
    boundary.clear();
  }
};

// A constraint segment for triangulateSegments().
struct Segment2 {
  glm::dvec2 a, b;
};

// Triangulates a polygon with holes using the even-odd rule over all rings:
// a triangle is kept when a path from it to infinity crosses the ring edges
// an odd number of times. So holes are empty, both lobes of a bow-tie are
// kept, and where two holes overlap the area counts as inside again (three
// crossings). An edge walked twice (a hole sharing an edge with the outer
// ring or with another hole, a spike in a ring) does not flip in/out.
//
// Returns false (and a reason) when the outer ring has fewer than 3 distinct
// points, no area (all collinear), a coordinate is not finite, or no triangle
// is kept. Inner rings with fewer than 3 distinct points are ignored.
bool triangulate(const Polygon2& poly, Triangulation& out, std::string& why);

// Triangulates the convex hull of arbitrary segments (which may cross, touch,
// repeat or dangle) and keeps the triangles for which inside(centroid) is
// true. Meant for street-block ground polygons whose boundary walks some
// edges twice (dead-end streets), where the parity rule cannot decide.
// Zero-length segments are ignored. Returns false when a coordinate is not
// finite, the segments span no area, or no triangle is kept. `points`, if
// given, are inserted as vertices too (Steiner points), after the segments.
bool triangulateSegments(const std::vector<Segment2>& segments,
                         const std::function<bool(glm::dvec2)>& inside, Triangulation& out,
                         std::string& why, const std::vector<glm::dvec2>* points = nullptr);

// Shoelace area of a ring: positive when counter-clockwise (x east, y north).
double signedArea(const Ring& ring);

// Sum of the (signed) triangle areas; equals the covered area when all
// triangles are counter-clockwise.
double area(const Triangulation& t);

}  // namespace blvd::bake
