#include "graph/route.h"

#include <algorithm>

#include <glm/geometric.hpp>

#include "core/rng.h"

namespace blvd::graph {
namespace {

// Streets a seeded route may start on: 30 m or longer, residential or above,
// not in a tunnel, with somewhere to go.
std::vector<uint32_t> startStreets(const StreetGraph& g) {
  std::vector<uint32_t> starts;
  for (uint32_t h = 0; h < g.halfedges.size(); ++h)
    if (g.halfedges[h].length >= 30 && g.halfedges[h].road_class <= RoadClass::Residential &&
        !(g.halfedges[h].flags & kTunnel) && g.successors.count(h) > 0)
      starts.push_back(h);
  if (starts.empty()) starts.push_back(0);
  return starts;
}

// The successor of `h` to drive next, or kNone. Noise is drawn for every
// candidate in successor order, so a seed gives one route.
uint32_t nextCell(const StreetGraph& g, uint32_t h, const std::vector<uint32_t>& visits, const RouteRules& rules,
                  core::Rng& rng) {
  const glm::dvec2 d = cellDirection(g, h, true);
  uint32_t best = kNone;
  double best_score = -1e9;
  for (const uint32_t* s = g.successors.begin(h); s != g.successors.end(h); ++s) {
    const HalfEdge& e = g.halfedges[*s];
    if ((e.flags & kTunnel) || e.pts_count < 2 || (!rules.revisit && visits[*s])) continue;
    double score = glm::dot(d, cellDirection(g, *s, false)) + 0.6 * rng.uniform();
    if (rules.revisit) score -= 3.0 * visits[*s] + (*s == g.halfedges[h].twin ? 10.0 : 0.0);
    if (score > best_score) best_score = score, best = *s;
  }
  return best;
}

}  // namespace

std::vector<uint32_t> seededRoute(const StreetGraph& g, const RouteRules& rules) {
  std::vector<uint32_t> route;
  if (g.halfedges.empty() || rules.cells == 0) return route;
  core::Rng rng(rules.seed);
  const std::vector<uint32_t> starts = startStreets(g);
  std::vector<uint32_t> visits(g.halfedges.size());
  const auto visit = [&](uint32_t h) {
    ++visits[h];
    if (!rules.revisit && g.halfedges[h].twin < visits.size()) ++visits[g.halfedges[h].twin];
  };
  for (int attempt = 0; attempt < std::max(1, rules.attempts) && route.size() < rules.cells; ++attempt) {
    std::fill(visits.begin(), visits.end(), 0u);
    const uint64_t pick = rng.next();  // drawn either way: a given start does not shift the turns' noise
    std::vector<uint32_t> r{rules.first < g.halfedges.size() ? rules.first : starts[pick % starts.size()]};
    visit(r[0]);
    while (r.size() < rules.cells) {
      const uint32_t next = nextCell(g, r.back(), visits, rules, rng);
      if (next == kNone) break;
      r.push_back(next);
      visit(next);
    }
    if (r.size() > route.size()) route = std::move(r);
  }
  return route;
}

}  // namespace blvd::graph
