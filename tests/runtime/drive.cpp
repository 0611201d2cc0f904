#include "drive.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include <gtest/gtest.h>

#include "stream/city.h"
#include "stream/residency.h"

namespace blvd_test {

Drive makeDrive(const blvd::graph::StreetGraph& g, uint32_t start, uint32_t cells, double step_m) {
  Drive d;
  std::vector<bool> seen(g.cellCount(), false);
  uint32_t c = start;
  while (c != blvd::graph::kNone && d.cells.size() < cells) {
    d.cells.push_back(c);
    seen[c] = true;
    // The successor with the smallest turn, preferring cells not driven yet
    // and a U-turn only at a dead end.
    const double h = blvd::stream::cellEndHeading(g, c);
    uint32_t next = blvd::graph::kNone;
    double best = 1e18;
    for (const uint32_t* s = g.successors.begin(c); s != g.successors.end(c); ++s) {
      double cost = std::fabs(std::fmod(blvd::stream::cellStartHeading(g, *s) - h + 540.0, 360.0) - 180.0);
      if (seen[*s]) cost += 1e6;
      if (g.halfedges[*s].twin == c) cost += 1e9;
      if (cost < best) best = cost, next = *s;
    }
    c = next;
  }
  for (uint32_t cell : d.cells) {
    const auto& e = g.halfedges[cell];
    double carry = 0;
    for (uint32_t i = 0; i + 1 < e.pts_count; ++i) {
      const glm::dvec2 a = g.points[e.pts_begin + i], b = g.points[e.pts_begin + i + 1];
      const double len = glm::length(b - a);
      if (len < 1e-6) continue;
      double heading = std::atan2(b.x - a.x, b.y - a.y) * 180.0 / 3.14159265358979323846;
      if (heading < 0) heading += 360.0;
      for (double t = carry; t < len; t += step_m) {
        const glm::dvec2 p = a + (b - a) * (t / len);
        d.poses.push_back({p.x, p.y, heading, cell});
      }
      carry = std::fmod(carry - len, step_m);
      if (carry < 0) carry += step_m;
    }
  }
  return d;
}

Drive impostorDrive(uint32_t cells, double step_m) {
  blvd::stream::City city;
  std::string err;
  EXPECT_EQ(city.open(BLVD_TEST_PACKAGE, err), blvd::core::Status::Ok) << err;
  uint32_t start = 0;
  for (uint32_t c = 0; c < city.cellTables().impostors.size(); ++c)
    if (!city.cellTables().impostors[c].layered.empty()) {
      start = c;
      break;
    }
  return makeDrive(city.graph(), start, cells, step_m);
}

}  // namespace blvd_test
