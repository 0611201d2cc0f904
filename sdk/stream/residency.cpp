#include "stream/residency.h"
#include "core/math.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

namespace blvd::stream {
namespace {
constexpr size_t kOpenCapacity = 256;  // frontier bound; the graph's out-degree is small

double headingOf(glm::dvec2 d) {
  double h = std::atan2(d.x, d.y) * core::kRadToDeg;
  return h < 0 ? h + 360.0 : h;
}
double turnAngle(double from_deg, double to_deg) {
  double d = std::fmod(to_deg - from_deg + 540.0, 360.0) - 180.0;
  return std::fabs(d);
}
}  // namespace

double cellStartHeading(const graph::StreetGraph& g, uint32_t c) {
  return headingOf(graph::cellDirection(g, c, false));
}

double cellEndHeading(const graph::StreetGraph& g, uint32_t c) { return headingOf(graph::cellDirection(g, c, true)); }

double cellStartHeading(const graph::GraphSource& g, uint32_t c) {
  return headingOf(graph::cellDirection(g, c, false));
}

double cellEndHeading(const graph::GraphSource& g, uint32_t c) { return headingOf(graph::cellDirection(g, c, true)); }

Residency::Residency(const graph::StreetGraph& g, uint32_t max_cells, uint32_t route_capacity)
    : owned_(std::make_unique<graph::MemoryGraph>(g)), g_(*owned_), max_cells_(std::max(1u, max_cells)) {
  wanted_.resize(max_cells_);
  open_.reserve(kOpenCapacity);
  route_.resize(route_capacity);
}

Residency::Residency(const graph::GraphSource& g, uint32_t max_cells, uint32_t route_capacity)
    : g_(g), max_cells_(std::max(1u, max_cells)) {
  wanted_.resize(max_cells_);
  open_.reserve(kOpenCapacity);
  route_.resize(route_capacity);
}

bool Residency::setRoute(const uint32_t* cells, size_t n) {
  route_n_ = 0;
  route_at_ = 0;
  if (n > route_.size()) return false;
  for (size_t i = 0; i < n; ++i)
    if (cells[i] >= g_.cellCount()) return false;
  std::copy(cells, cells + n, route_.begin());
  route_n_ = n;
  return true;
}

double Residency::turnPenalty(double turn_deg, double speed_mps) {
  // 90° costs 20 m standing still and 20 m more for every 10 m/s.
  return turn_deg / 90.0 * (20.0 + 2.0 * std::max(0.0, speed_mps));
}

void Residency::update(const Motion& m) {
  wanted_n_ = 0;
  current_ = m.cell;
  if (m.cell == graph::kNone || m.cell >= g_.cellCount()) return;
  auto want = [&](uint32_t c) {
    if (wanted_n_ >= max_cells_) return false;
    for (size_t i = 0; i < wanted_n_; ++i)
      if (wanted_[i] == c) return true;
    wanted_[wanted_n_++] = c;
    return true;
  };
  want(m.cell);

  // The route, from the current cell on.
  if (route_n_) {
    const size_t at = routeIndex(m.cell);
    if (at < route_n_) route_at_ = at;
    for (size_t i = at + 1; i < route_n_ && wanted_n_ < max_cells_; ++i) want(route_[i]);
    if (at < route_n_) return;  // on the route: its cells are what comes next
  }

  // Best-first over successors (Dijkstra order on metres + turn penalties).
  open_.clear();
  const double left = std::max(0.0, double(g_.halfedge(m.cell).length) - m.arc_m);
  auto push = [&](uint32_t from, double base) {
    const double h = cellEndHeading(g_, from);
    for (uint32_t s : g_.successors(from)) {
      if (open_.size() >= kOpenCapacity) return;
      const double cost = base + turnPenalty(turnAngle(h, cellStartHeading(g_, s)), m.speed_mps);
      open_.push_back({cost, s});
    }
  };
  push(m.cell, left);
  while (!open_.empty() && wanted_n_ < max_cells_) {
    auto best = std::min_element(open_.begin(), open_.end(), [](const Open& a, const Open& b) {
      return a.cost < b.cost || (a.cost == b.cost && a.cell < b.cell);
    });
    const Open o = *best;
    *best = open_.back();
    open_.pop_back();
    bool seen = false;
    for (size_t i = 0; i < wanted_n_; ++i) seen |= wanted_[i] == o.cell;
    if (seen) continue;
    want(o.cell);
    push(o.cell, o.cost + g_.halfedge(o.cell).length);
  }
}

size_t Residency::routeIndex(uint32_t cell) const {
  for (size_t i = route_at_; i < route_n_; ++i)
    if (route_[i] == cell) return i;
  for (size_t i = 0; i < std::min(route_at_, route_n_); ++i)
    if (route_[i] == cell) return i;
  return route_n_;
}

uint32_t Residency::nextOnRoute(uint32_t cell) const {
  const size_t at = routeIndex(cell);
  return at + 1 < route_n_ ? route_[at + 1] : graph::kNone;
}

uint32_t Residency::rank(uint32_t cell) const {
  for (size_t i = 0; i < wanted_n_; ++i)
    if (wanted_[i] == cell) return static_cast<uint32_t>(i);
  return graph::kNone;
}

uint32_t Residency::victim(const uint32_t* resident, size_t n, uint32_t for_rank, const bool* kept) const {
  auto may_go = [&](size_t i) { return !kept || !kept[i]; };
  for (size_t i = 0; i < n; ++i)
    if (resident[i] == graph::kNone && may_go(i)) return static_cast<uint32_t>(i);
  // Unwanted cells: the furthest from where the current cell starts.
  const glm::dvec2 here =
      current_ < g_.cellCount() ? g_.point(g_.halfedge(current_).pts_begin) : glm::dvec2(0, 0);
  uint32_t best = graph::kNone;
  double best_d = -1;
  for (size_t i = 0; i < n; ++i) {
    if (!may_go(i) || rank(resident[i]) != graph::kNone) continue;
    const double d = glm::length(g_.point(g_.halfedge(resident[i]).pts_begin) - here);
    if (d > best_d) best_d = d, best = static_cast<uint32_t>(i);
  }
  if (best != graph::kNone) return best;
  // All wanted: give up the least wanted, if it ranks below the newcomer.
  uint32_t worst_rank = 0;
  for (size_t i = 0; i < n; ++i) {
    const uint32_t r = rank(resident[i]);
    if (may_go(i) && r > for_rank && r >= worst_rank) worst_rank = r, best = static_cast<uint32_t>(i);
  }
  return best;
}

}  // namespace blvd::stream
