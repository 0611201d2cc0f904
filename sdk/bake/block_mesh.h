// Geometry of one city block (one face of the street map): its ground polygon,
// the half of every bordering street that lies on the block's side, and its
// buildings. Sillion 97 §4.1 draws "the blocks touching the street" as the
// local model, so each block carries the street surface around it: drawing a
// cell's local blocks draws its streets too.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "bake/osm_reader.h"
#include "geo/mesh.h"
#include "graph/street_graph.h"

namespace blvd::bake {

// Heights above the ground plane (y = 0), metres, so coplanar layers sort.
constexpr double kGroundLift = 0.03;
constexpr double kStreetLift = 0.06;
// Where two streets' ribbons overlap (every junction, a slip road beside its
// carriageway), the one on top is chosen here, not left to the depth buffer:
// at one height the two fought, rows of one grey through the other that
// shimmer as the car moves. Each rank lifts a ribbon this much more: a major
// road (secondary and up) one, a bridge two. Two centimetres are more than
// 100 times the depth buffer's step along a grazing ray at the view distance.
constexpr double kStreetRankLift = 0.02;

// The lift of half-edge e's ribbon: kStreetLift plus its rank's.
double streetLift(const graph::HalfEdge& e);

struct BlockMeshStats {
  size_t buildings = 0, building_triangles = 0, ground_triangles = 0, street_triangles = 0;
  size_t skipped_buildings = 0;  // footprints that could not be used (counted warning)
};

// Half-width street ribbon on the left of half-edge h (the side of its face),
// with mitred joints, at streetLift(e); its ends reach half a metre past the
// street's end points, so that streets meeting at an angle overlap. Tunnels
// get no ribbon: they are under the block.
void appendHalfStreet(const graph::StreetGraph& g, uint32_t h, geo::MeshData& out);

// Ground polygon of face f: all of its boundary half-edges as constraints,
// triangles kept where inside(p) says p lies in f. False if there is none (the
// unbounded face, or a sliver).
bool appendBlockGround(const graph::StreetGraph& g, uint32_t f, const std::function<bool(glm::dvec2)>& inside,
                       geo::MeshData& out, std::string& why);

// A point surely inside the footprint (the centroid of its largest triangle),
// so a building on a curved or L-shaped lot is placed by where it stands.
bool buildingAnchor(const OsmBuilding& b, glm::dvec2& p);

// One building as an extruded prism per polygon (flat roof).
bool appendBuilding(const OsmBuilding& b, geo::MeshData& out, std::string& why);

}  // namespace blvd::bake
