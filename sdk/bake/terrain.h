// The ground's height under the bake's geometry, and the geometry put on it.
//
// Heights are metres above the package's origin height (its frame's h0), at a
// local east/north point, bilinear in the DEM (bake/dem.h); the frame's
// tangent plane is taken as level (the earth's curvature, 8 cm at 1 km, is
// left out as it is for the flat city).
//
// The rules:
// - A building stands at the lowest ground under its footprint: its base is
//   the minimum of the terrain over the footprint's vertices and the DEM
//   samples inside it, so no wall floats; on a slope the uphill walls start
//   below the ground. Parts with min_height keep their offset above that base.
// - Ground and street surfaces are draped: their triangles are split where
//   an edge's midpoint lies off the terrain by more than a tolerance, or the
//   edge is long (longest-edge bisection, each edge split at one shared
//   midpoint, so neighbours stay joined; DrapeTolerance), then every vertex
//   is lifted by the terrain under it, keeping its own lift above the ground
//   (kGroundLift, kStreetLift), and normals are recomputed from the draped
//   triangles.
#pragma once
#include <functional>

#include <glm/vec2.hpp>

#include "bake/dem.h"
#include "bake/triangulate.h"
#include "geo/local_frame.h"
#include "geo/mesh.h"

namespace blvd::bake {

// The terrain in a package's frame: height(east, north) in metres above h0.
using TerrainHeight = std::function<double(glm::dvec2 en)>;

// From a DEM: the frame's reverse projection, then Dem::height. Points the
// DEM does not cover are a bug here (the bake checks coverage first): they
// throw core::Error(Internal) naming the point.
TerrainHeight demTerrain(const Dem& dem, const geo::LocalFrame& frame);
// The same, NaN where the DEM has no height (the terrain tiles' margin).
TerrainHeight demHeights(const Dem& dem, const geo::LocalFrame& frame);

// Splits m's triangles (positions in glTF axes: x east, y up, z = -north) until
// no edge measured in the horizontal plane is longer than max_edge_m. New
// vertices interpolate their parents' attributes.
void subdivideLongEdges(geo::MeshData& m, double max_edge_m);

// The same, adaptively: an edge is split when it is longer than
// `max_edge_m`, or longer than `min_edge_m` with the terrain at its midpoint
// more than `height_m` off the straight line between its ends (the edge
// alone decides, so both its triangles split it alike).
// The DEM's bilinear surface has creases along its grid lines, where no
// straight edge follows it: `min_edge_m` stops the splitting there, and the
// street ribbons stand kTerrainStreetLift higher on terrain than on flat
// ground, so the ground between two of its vertices stays under them.
struct DrapeTolerance {
  double max_edge_m = 48.0;  // about half SRTM3's 90 m spacing: every DEM cell is sampled
  double min_edge_m = 6.0;
  double height_m = 0.05;
};
constexpr double kTerrainStreetLift = 0.15;  // at most, metres added to a draped street ribbon (about a kerb)

// Raises each vertex by `per_slope_m` times the terrain's slope under it (rise
// over run), at most `max_m`: the room a straight edge of the draped ground
// may need over a crease of that slope, so the street ribbon stays above the
// ground there; on level ground nothing moves.
void raiseBySlope(geo::MeshData& m, const TerrainHeight& terrain, double per_slope_m, double max_m);
void subdivideForTerrain(geo::MeshData& m, const TerrainHeight& terrain, const DrapeTolerance& tol);

// Adds the terrain under each vertex to its height (y) and recomputes the
// normals from the triangles (area-weighted), for meshes that lie on the ground.
void drapeOnTerrain(geo::MeshData& m, const TerrainHeight& terrain);

// Raises every vertex of m by dy metres (a building onto its base).
void raise(geo::MeshData& m, double dy);

// The lowest terrain under a footprint: its vertices' heights and those of a
// grid of points inside it at `step_m` (the DEM's sample spacing or finer).
double lowestUnder(const std::vector<Polygon2>& footprint, const TerrainHeight& terrain, double step_m);

}  // namespace blvd::bake
