// The local model of every cell (Sillion 97 §4.1): the blocks drawn as
// geometry while the viewer is on the cell, everything else being the
// cell's impostors. street_map's computeCellLists gives the paper's
// topological choice, the blocks that touch the street or share one of its
// end junctions. The paper notes that "other definitions can be used" and
// that "the chosen selection mechanism should depend on the particular
// morphology of the city model". Where a thin face (a traffic island, the
// strip between a road and its service road) lies between the street and
// the next block, that next block's buildings stand a few metres from the
// driver but are not topologically near: drawn as an impostor from a
// vantage point tens of metres back, they smear and uncover what no capture
// saw. So a block is local too when one of its buildings comes within a
// radius of the street (docs/decisions/0015), when it has no building and
// its ground comes within that radius (an island between carriageways,
// seen below the horizon more steeply than a capture holds), and when its ground borders a
// street within a few metres of the cell's end points: a junction drawn as
// several vertices (a dual carriageway crossing, a short connector) puts the
// crossing street's blocks right under a viewer at the cell's end, where the
// runtime keeps the cell (runtime/cell_choice.h), yet they share no vertex
// with it; drawn as impostors from half a run back, their street surfaces
// smear across the near street (docs/decisions/0025).
#pragma once
#include <cstdint>
#include <vector>

#include "bake/osm_reader.h"
#include "graph/street_graph.h"

namespace blvd::bake {

// Appends to each cell's local blocks (g.local_blocks) every bounded block
// with a building footprint (outer ring) within `radius_m` of the cell's
// polyline, or with no building and a street of its border within
// `radius_m` of the cell's (its ground), in block order after the
// topological ones. radius_m <= 0: no change. `face_buildings[f]` lists block f's buildings (indices into
// `buildings`). Then every bounded block on either side of a street segment
// within `junction_radius_m` of the cell's first or last point (<= 0: none).
// Both half-edges of a street get the same added blocks.
void widenLocalModels(graph::StreetGraph& g, const std::vector<OsmBuilding>& buildings,
                      const std::vector<std::vector<uint32_t>>& face_buildings, double radius_m,
                      double junction_radius_m = 0.0);

}  // namespace blvd::bake
