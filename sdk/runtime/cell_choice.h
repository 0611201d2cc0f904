// The cell of a pose the host set (blvd_set_pose_*). At a junction a pose is
// about as near the cross street's cells as the one it drives along, and the
// nearest cell alone flickers to a neighbour for a frame or two: a cell that
// is not resident (the frame is degraded, and the cell is fetched for
// nothing) and a false boundary. A host-set pose has no map matcher to keep
// it on its street (the tracker's HMM does that for fed poses), so the last
// cell is kept while the pose lies along it, and at its end the route's next
// cell or a successor takes over, each while it costs within kStickM of the
// nearest. A pose moved far away (a jump) goes by the nearest cell.
#pragma once
#include <cstdint>

#include <glm/vec2.hpp>

#include "graph/street_graph.h"
#include "stream/city.h"
#include "stream/residency.h"

namespace blvd::runtime {

class CellChoice {
 public:
  static constexpr double kStickM = 3.0;

  CellChoice(const stream::City& city, const stream::Residency& residency) : city_(city), residency_(residency) {}
  // The cell of a host-set pose at `p` heading `heading_deg`, and the arc
  // length along it; kNone only for a map without streets (the caller keeps
  // poses off the map away: Runtime::currentCell). The same pose asked again (a
  // degraded frame drawn again after blvd_wait_resident) gets the same
  // answer: a second step from the answer itself would move on a cell.
  uint32_t choose(glm::dvec2 p, double heading_deg, double& arc_m);
  // The tracker placed this frame's camera: the next host pose starts afresh.
  void forget() { last_cell_ = graph::kNone, has_last_pose_ = false; }

 private:
  uint32_t continued(uint32_t cell, double cost, glm::dvec2 p, double heading_deg, double& arc_m) const;

  const stream::City& city_;
  const stream::Residency& residency_;
  uint32_t last_cell_ = graph::kNone;
  bool has_last_pose_ = false;
  glm::dvec2 last_p_{0, 0};
  double last_heading_ = 0, last_arc_ = 0;
};

}  // namespace blvd::runtime
