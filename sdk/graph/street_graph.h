// The street graph as a planar half-edge map (Sillion 97 §4.1: "the street
// network is a planar map whose faces are the city blocks"). Junctions are
// vertices, street segments between junctions are edges with their polylines,
// each edge is a pair of twin half-edges, faces are blocks.
//
// A *cell* is one half-edge: a vehicle on that street, going that way
// (Sillion 97 §4.1). Cells carry their successors and predecessors at their
// end junctions and their local block list (the blocks on both sides plus the
// blocks sharing its end junctions).
//
// Grade-separated crossings (bridges, tunnels, `layer`) split edges at a
// `Crossing` vertex so the map stays planar and the faces stay real blocks, but
// a crossing is not a junction: a cell entering one continues only along its own
// way.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec2.hpp>

namespace blvd::graph {

constexpr uint32_t kNone = 0xffffffffu;

enum class VertexKind : uint8_t { Junction = 0, DeadEnd = 1, Crossing = 2, Bend = 3 };

// Road classes, ordered roughly by importance. Stored per edge.
enum class RoadClass : uint8_t {
  Motorway, Trunk, Primary, Secondary, Tertiary, Unclassified, Residential, LivingStreet, Service, Link, Other
};

struct Vertex {
  glm::dvec2 p{0, 0};       // local east/north metres
  VertexKind kind = VertexKind::Junction;
  uint32_t halfedge = kNone; // one half-edge leaving this vertex
};

enum HalfEdgeFlags : uint8_t { kOneway = 1, kBridge = 2, kTunnel = 4, kReverseOfOneway = 8 };

struct HalfEdge {
  uint32_t origin = kNone;
  uint32_t twin = kNone;
  uint32_t next = kNone;  // next half-edge around the same face (face on the left)
  uint32_t face = kNone;
  uint32_t pts_begin = 0; // polyline in StreetGraph::points, from origin to the twin's origin
  uint32_t pts_count = 0;
  float length = 0;       // metres along the polyline
  float width = 0;        // carriageway width, metres
  RoadClass road_class = RoadClass::Other;
  uint8_t flags = 0;
  int8_t layer = 0;
  int64_t osm_way = 0;    // the way this street segment starts on
};

struct Face {
  uint32_t halfedge = kNone; // a half-edge on the outer boundary; kNone for the unbounded face
  bool unbounded = false;
  double area = 0;           // of the outer boundary, m^2 (0 for the unbounded face)
};

// Variable-length per-cell lists, stored CSR-style: list i is
// items[offsets[i] .. offsets[i+1]).
struct Csr {
  std::vector<uint32_t> offsets{0};
  std::vector<uint32_t> items;
  size_t size() const { return offsets.size() - 1; }
  const uint32_t* begin(size_t i) const { return items.data() + offsets[i]; }
  const uint32_t* end(size_t i) const { return items.data() + offsets[i + 1]; }
  size_t count(size_t i) const { return offsets[i + 1] - offsets[i]; }
  void push(const std::vector<uint32_t>& list) {
    items.insert(items.end(), list.begin(), list.end());
    offsets.push_back(static_cast<uint32_t>(items.size()));
  }
};

struct StreetGraph {
  std::vector<Vertex> vertices;
  std::vector<HalfEdge> halfedges;  // also the cells: cell i == half-edge i
  std::vector<Face> faces;          // also the blocks: block i == face i
  std::vector<glm::dvec2> points;   // polyline storage
  Csr successors;                   // per cell
  Csr predecessors;                 // per cell
  Csr local_blocks;                 // per cell

  size_t cellCount() const { return halfedges.size(); }
  uint32_t endVertex(uint32_t h) const { return halfedges[halfedges[h].twin].origin; }
  size_t junctionCount() const;
  // Number of connected components of the vertex/edge graph.
  size_t componentCount() const;
};

// Checks the half-edge invariants; returns one line per violation (empty = ok):
// every half-edge has a twin, a next and a face; twin(twin(h)) == h; next(h)
// starts where h ends; walking next returns to h with the same face; polylines
// join their vertices; V - E + F == U + C (Euler for a planar map with C
// components and U = 1 unbounded face; a tiled benchmark package is U planar
// maps side by side, each with its own); cell lists are in range.
std::vector<std::string> checkInvariants(const StreetGraph& g);

// Binary (de)serialisation for the package's GRPH and CELL sections. `parse`
// bounds-checks everything and throws core::Error(Corrupt) naming `what` and
// the offset; it also runs the structural checks so a package cannot hand the
// runtime an out-of-range index.
std::vector<uint8_t> serializeGraph(const StreetGraph& g);
std::vector<uint8_t> serializeCells(const StreetGraph& g);
// A graph point farther than this from the package's origin (metres, either
// axis) is refused by the readers (parseGraph, stream::PagedGraph).
constexpr double kMaxPointM = 1e7;
void parseGraph(const uint8_t* data, size_t size, uint64_t file_offset, StreetGraph& g);
void parseCells(const uint8_t* data, size_t size, uint64_t file_offset, StreetGraph& g);

const char* roadClassName(RoadClass c);

// Unit direction of cell `h`'s polyline at its start or end ((1, 0) for a
// degenerate one): where a route leaves or enters a junction.
glm::dvec2 cellDirection(const StreetGraph& g, uint32_t h, bool at_end);

}  // namespace blvd::graph
