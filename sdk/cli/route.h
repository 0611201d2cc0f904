// Deterministic drives along the street graph for `blvd view --path` (and the
// route benchmarks later): a chain of connected cells and camera poses sampled
// along it.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "graph/street_graph.h"

namespace blvd::cli {

struct Pose {
  double x = 0, y = 0;      // local east/north metres
  double heading_deg = 0;   // clockwise from north
  uint32_t cell = 0;
};

// N connected cells from a seeded start (a street of at least 30 m): prefers
// going straight on at junctions and cells not yet driven; U-turns only at
// dead ends. Deterministic for a graph and seed.
std::vector<uint32_t> autoRoute(const graph::StreetGraph& g, uint32_t cells, uint64_t seed);

// Poses every `step_m` metres along the route, heading toward a point
// `look_ahead_m` further on (so turns are smooth), offset `lateral_m` to the right.
std::vector<Pose> samplePoses(const graph::StreetGraph& g, const std::vector<uint32_t>& route, double step_m,
                              double look_ahead_m = 10.0, double lateral_m = 1.8);

}  // namespace blvd::cli
