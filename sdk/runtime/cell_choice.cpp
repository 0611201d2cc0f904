#include "runtime/cell_choice.h"

namespace blvd::runtime {

uint32_t CellChoice::choose(glm::dvec2 p, double heading_deg, double& arc_m) {
  if (has_last_pose_ && p == last_p_ && heading_deg == last_heading_) {
    arc_m = last_arc_;
    return last_cell_;
  }
  double cost = 0;
  uint32_t cell = city_.nearestCell(p, heading_deg, &arc_m, &cost);
  try {
    if (cell != graph::kNone) cell = continued(cell, cost, p, heading_deg, arc_m);
  } catch (const core::Error& e) {
    // The last cell's table pages are not here (a package on a server) and
    // the link cannot bring them now: the nearest cell, without the
    // stickiness. When it can, the frame waits for them like any other page.
    if (e.status() != core::Status::Unavailable || city_.linkMayBringTables()) throw;
  }
  last_cell_ = cell;
  has_last_pose_ = true, last_p_ = p, last_heading_ = heading_deg, last_arc_ = arc_m;
  return cell;
}

uint32_t CellChoice::continued(uint32_t cell, double cost, glm::dvec2 p, double heading_deg, double& arc_m) const {
  if (last_cell_ == graph::kNone || last_cell_ >= city_.streets().cellCount() || cell == last_cell_) return cell;
  double arc = 0;
  bool at_end = false;
  if (city_.cellCost(last_cell_, p, heading_deg, &arc, &at_end) <= cost + kStickM && !at_end) {
    arc_m = arc;
    return last_cell_;
  }
  uint32_t pick = graph::kNone;
  double pick_cost = cost + kStickM, pick_arc = 0;
  auto consider = [&](uint32_t c) {
    double a = 0;
    const double k = city_.cellCost(c, p, heading_deg, &a, nullptr);
    if (k <= pick_cost) pick = c, pick_cost = k, pick_arc = a;
  };
  const uint32_t next = residency_.nextOnRoute(last_cell_);
  if (next != graph::kNone) consider(next);
  if (pick == graph::kNone)
    for (uint32_t s : city_.streets().successors(last_cell_)) consider(s);
  if (pick == graph::kNone) return cell;
  arc_m = pick_arc;
  return pick;
}

}  // namespace blvd::runtime
