// Which cells should be resident, in priority order, and which resident cell
// to release first ("Streaming"). Pure: no GL, no I/O, no heap after
// construction, so the runtime can call it every frame on the render thread.
//
// The current cell comes first. With a route set, the route's next cells
// follow. Otherwise the street graph is expanded best-first along successor
// cells with a cost in metres: the path length plus a turn penalty that grows
// with the turning angle and the speed (a fast car rarely takes a sharp turn),
// so "straight on" is fetched before side streets. The furthest resident cell
// that is no longer wanted is released first.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "graph/graph_source.h"
#include "graph/street_graph.h"

namespace blvd::stream {

struct Motion {
  uint32_t cell = graph::kNone;  // current cell
  double arc_m = 0;              // position along it
  double speed_mps = 0;
};

class Residency {
 public:
  // `max_cells` is the number of cell slots (at least 1); a route holds at
  // most `route_capacity` cells.
  // The source must outlive the residency.
  Residency(const graph::GraphSource& g, uint32_t max_cells, uint32_t route_capacity);
  // Over a whole graph in memory (tests, tools).
  Residency(const graph::StreetGraph& g, uint32_t max_cells, uint32_t route_capacity);

  // Sets (or, with n == 0, clears) a route of cells, copied into the buffer
  // sized at construction. False when n > route_capacity or a cell is out of
  // range (the route is then cleared).
  bool setRoute(const uint32_t* cells, size_t n);

  // Fills wanted() with up to max_cells cells, most wanted first. Makes no
  // heap allocation.
  void update(const Motion& m);
  const uint32_t* wanted() const { return wanted_.data(); }
  // The cell after `cell` on the route, or kNone. A route may pass a cell
  // more than once (a loop round a block): the visit is the first at or after
  // the route position update() last found, else the first of all.
  uint32_t nextOnRoute(uint32_t cell) const;
  size_t wantedCount() const { return wanted_n_; }
  bool hasRoute() const { return route_n_ > 0; }
  // Rank of `cell` in wanted() or kNone.
  uint32_t rank(uint32_t cell) const;

  // Of `resident[0..n)` (kNone entries are empty slots), the index of the slot
  // to fill next for a cell of rank `for_rank`: an empty slot first, else the
  // unwanted cell furthest from the current cell's start, else the wanted cell
  // of lowest priority if that is below `for_rank`; kNone when nothing may go.
  // Slots whose `kept[i]` is true (the runtime copies blocks from them) never go.
  uint32_t victim(const uint32_t* resident, size_t n, uint32_t for_rank, const bool* kept = nullptr) const;

  // The turn penalty in metres for a heading change of `turn_deg` at `speed`.
  static double turnPenalty(double turn_deg, double speed_mps);

 private:
  struct Open {
    double cost;
    uint32_t cell;
  };
  // The visit of `cell` at or after route_at_, else the first; route_n_ if none.
  size_t routeIndex(uint32_t cell) const;

  std::unique_ptr<graph::MemoryGraph> owned_;
  const graph::GraphSource& g_;
  uint32_t max_cells_;
  std::vector<uint32_t> wanted_;
  size_t wanted_n_ = 0;
  std::vector<Open> open_;  // best-first frontier, bounded
  std::vector<uint32_t> route_;
  size_t route_n_ = 0;
  size_t route_at_ = 0;  // index of the current cell's visit on the route
  uint32_t current_ = graph::kNone;
};

// Heading of a cell's polyline at its start / end, degrees clockwise from north.
double cellStartHeading(const graph::StreetGraph& g, uint32_t cell);
double cellEndHeading(const graph::StreetGraph& g, uint32_t cell);
double cellStartHeading(const graph::GraphSource& g, uint32_t cell);
double cellEndHeading(const graph::GraphSource& g, uint32_t cell);

}  // namespace blvd::stream
