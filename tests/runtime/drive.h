// A deterministic drive through a package for the runtime tests: from a start
// cell, follow successors (the straightest one not yet visited) and sample a
// pose every `step_m` metres along the cells' polylines.
#pragma once
#include <cstdint>
#include <vector>

#include "graph/street_graph.h"

namespace blvd_test {

struct DrivePose {
  double x, y, heading_deg;
  uint32_t cell;
};

struct Drive {
  std::vector<uint32_t> cells;
  std::vector<DrivePose> poses;
};

Drive makeDrive(const blvd::graph::StreetGraph& g, uint32_t start, uint32_t cells, double step_m);

// makeDrive on the test package (BLVD_TEST_PACKAGE) from its first cell with
// impostors, so that textures stream too.
Drive impostorDrive(uint32_t cells, double step_m);

}  // namespace blvd_test
