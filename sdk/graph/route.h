// Seeded drives along the street graph: a chain of connected cells from a
// start street, for `blvd view --path`, the route, budget and memory
// benchmarks, the bake's route selection and the drive simulator (track/sim).
// Straight on scores highest at a junction and seeded noise picks among the
// turns; a U-turn only where nothing else is left. Deterministic for a graph,
// rules and seed, with every standard library (core/rng.h).
#pragma once

#include <cstdint>
#include <vector>

#include "graph/street_graph.h"

namespace blvd::graph {

struct RouteRules {
  uint32_t cells = 0;     // cells in the route (fewer when the graph runs out)
  uint64_t seed = 1;
  uint32_t first = kNone; // the first cell; kNone: a seeded street of at least 30 m
  // true: a cell may be driven again at a cost per earlier visit, so a long
  // route in a small city loops (the views and benchmarks). false: no cell
  // (nor its twin) twice; the longest of `attempts` tries (the simulator,
  // whose truth is a cell sequence).
  bool revisit = true;
  int attempts = 1;
};

std::vector<uint32_t> seededRoute(const StreetGraph& g, const RouteRules& rules);

}  // namespace blvd::graph
