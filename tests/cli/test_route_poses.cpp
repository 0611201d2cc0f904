// Poses along a route (sdk/cli/route.h): a route that loops passes a cell
// more than once, and `visitPoses` gives each visit its own pose, halfway
// along it, in route order.
#include <gtest/gtest.h>

#include <vector>

#include "cli/route.h"

namespace blvd::cli {
namespace {

// Two half-edges of one straight street, 40 m east along y = 0 and back.
class Street final : public graph::GraphSource {
 public:
  uint32_t cellCount() const override { return 2; }
  uint32_t pointCount() const override { return 4; }
  graph::HalfEdge halfedge(uint32_t h) const override {
    graph::HalfEdge e;
    e.origin = h;
    e.twin = 1 - h;
    e.pts_begin = 2 * h;
    e.pts_count = 2;
    e.length = 40;
    return e;
  }
  glm::dvec2 point(uint32_t i) const override { return i == 0 || i == 3 ? glm::dvec2(0, 0) : glm::dvec2(40, 0); }
  void listBounds(graph::CellList, uint32_t, uint32_t* first, uint32_t* last) const override { *first = *last = 0; }
  uint32_t item(graph::CellList, uint32_t) const override { return 0; }
  void segmentsNear(double, double, double, EntryFn, void*) const override {}
  graph::GridShape gridShape() const override { return {}; }
  uint32_t gridEntryCount() const override { return 0; }
};

TEST(RoutePoses, ALoopGetsAPoseForEveryVisitInRouteOrder) {
  const Street g;
  const std::vector<uint32_t> route = {0, 1, 0, 1, 0};
  const std::vector<Pose> poses = visitPoses(g, route);
  ASSERT_EQ(poses.size(), route.size());
  for (size_t i = 0; i < poses.size(); ++i) {
    EXPECT_EQ(poses[i].cell, route[i]) << i;
    // Halfway along the visit (samples every metre; the pose stands 1.8 m to
    // the right of the street).
    EXPECT_NEAR(poses[i].x, 20.0, 1.0) << i;
    EXPECT_NEAR(std::abs(poses[i].y), 1.8, 1e-9) << i;
    EXPECT_NEAR(poses[i].heading_deg, route[i] == 0 ? 90.0 : 270.0, 1e-6) << i;
  }
}

}  // namespace
}  // namespace blvd::cli
