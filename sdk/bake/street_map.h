// Builds the planar half-edge street map (Sillion 97 §4.1) from OSM street
// polylines, with CGAL's 2D arrangement doing the planarisation exactly.
//
// Every street segment goes into the arrangement; CGAL splits segments where
// they cross and finds the faces (city blocks). We then contract degree-2
// vertices into polylines, so graph vertices are junctions, dead ends and
// grade-separated crossings only. A crossing (two streets meeting without a
// shared OSM node: a bridge over, a tunnel under, a different `layer`) stays a
// vertex of the planar map but connects a cell only to the continuation of its
// own way (see graph/street_graph.h).
#pragma once
#include <memory>
#include <vector>

#include <glm/vec2.hpp>

#include "bake/osm_reader.h"
#include "graph/street_graph.h"

namespace blvd::bake {

class StreetMap {
 public:
  explicit StreetMap(const std::vector<OsmStreet>& streets);
  ~StreetMap();
  StreetMap(const StreetMap&) = delete;
  StreetMap& operator=(const StreetMap&) = delete;

  graph::StreetGraph& graph() { return graph_; }
  const graph::StreetGraph& graph() const { return graph_; }
  // The face (block) containing p; points on a street go to the face on its left.
  uint32_t locateFace(const glm::dvec2& p) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  graph::StreetGraph graph_;
};

// Fills successors, predecessors and local block lists of every cell from the
// half-edge structure and the per-vertex connectivity (exposed for tests).
void computeCellLists(graph::StreetGraph& g, const std::vector<std::vector<uint32_t>>& connects_at_end);

}  // namespace blvd::bake
