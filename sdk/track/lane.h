// Where on a street a vehicle drives: the lane model shared by the tracker's
// map aid (tracker.cpp, the cross-track measurement's expected offset) and the
// drive simulator (sim.cpp, the path the simulated car follows), so the two
// cannot drift apart.
//
// Model: on a two-way street a vehicle keeps to its own side, `two_way_offset_m`
// right of the centre line (left under left-hand traffic: pass a negative
// offset); on a one-way street the whole carriageway is its side, so it keeps
// to the centre. The graph knows no lane counts (a carriageway width only), so
// a one-way street with several lanes is modelled by its centre too: the
// expected offset is then off by up to half the width, which the map aid's
// sigma and its agreement check (tracker.h) have to absorb.
#pragma once
#include "graph/street_graph.h"

namespace blvd::track {

// Signed offset from the half-edge's polyline, metres, positive to its right.
inline double laneOffset(const graph::HalfEdge& he, double two_way_offset_m) {
  return (he.flags & graph::kOneway) ? 0.0 : two_way_offset_m;
}

}  // namespace blvd::track
