// Camera poses along a route (graph/route.h's seededRoute) for `blvd view
// --path` and the route, budget and memory benchmarks.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "graph/graph_source.h"
#include "graph/route.h"
#include "graph/street_graph.h"

namespace blvd::cli {

struct Pose {
  double x = 0, y = 0;      // local east/north metres
  double heading_deg = 0;   // clockwise from north
  uint32_t cell = 0;
};

// Poses every `step_m` metres along the route, heading toward a point
// `look_ahead_m` further on (so turns are smooth), offset `lateral_m` to the right.
std::vector<Pose> samplePoses(const graph::GraphSource& g, const std::vector<uint32_t>& route, double step_m,
                              double look_ahead_m = 10.0, double lateral_m = 1.8);

// One pose per visit of a cell, halfway along the visit, in route order (as
// samplePoses places them, every metre): a route that loops passes a cell
// more than once and gets a pose each time.
std::vector<Pose> visitPoses(const graph::GraphSource& g, const std::vector<uint32_t>& route);

}  // namespace blvd::cli
