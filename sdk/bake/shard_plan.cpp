// Hilbert-ordered, cost-balanced shards; the contract is in shard_plan.h.
#include "bake/shard_plan.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include "bake/impostor_bake.h"
#include "bake/street_points.h"

namespace blvd::bake {
namespace {

constexpr uint32_t kHilbertSide = 1u << 16;  // grid over the city's bounds: cells under a metre in a 60 km city
// What one impostor capture costs in item-buffer samples, and how many
// captures a run takes (layers, plus the single impostor with --impostor
// both): see streetCost, measured in docs/cluster-bake.md.
constexpr double kCaptureSamples = 0.5;
constexpr double kLayersPerRun = 3.0;

}  // namespace

uint64_t hilbertIndex(uint32_t side, uint32_t x, uint32_t y) {
  // The classic xy -> d conversion: per level, the quadrant's offset, then the
  // rotation that makes the quadrant's sub-curve continue the parent's.
  uint64_t d = 0;
  for (uint32_t s = side / 2; s > 0; s /= 2) {
    const uint32_t rx = (x & s) ? 1u : 0u, ry = (y & s) ? 1u : 0u;
    d += uint64_t(s) * s * ((3u * rx) ^ ry);
    if (ry == 0) {
      if (rx == 1) x = side - 1 - x, y = side - 1 - y;
      std::swap(x, y);
    }
  }
  return d;
}

double streetCost(const graph::StreetGraph& g, uint32_t h, bool want_h, bool want_twin, const ImpostorOptions& opt) {
  const double samples = std::max(0, opt.positions_per_cell - 2) + 1.0;
  if (opt.mode == ImpostorMode::None) return samples;
  const double captures = (opt.mode == ImpostorMode::Single ? 0.0 : kLayersPerRun) +
                          (opt.mode == ImpostorMode::Layered ? 0.0 : 1.0);
  const double len = g.halfedges[h].length;
  const double runs = std::clamp(std::ceil(len / opt.run_length_m - 1e-9), 1.0, double(opt.max_runs));
  return samples + (int(want_h) + int(want_twin)) * runs * captures * kCaptureSamples;
}

ShardPlan planShards(const graph::StreetGraph& g, const std::vector<bool>& want, const ImpostorOptions& opt,
                     uint32_t count) {
  struct Street {
    uint64_t d;
    uint32_t h;
    double cost;
  };
  std::vector<Street> streets;
  glm::dvec2 lo(std::numeric_limits<double>::max()), hi(std::numeric_limits<double>::lowest());
  for (const glm::dvec2& p : g.points) lo = glm::min(lo, p), hi = glm::max(hi, p);
  const double extent = std::max({hi.x - lo.x, hi.y - lo.y, 1.0});
  auto cellOf = [&](double v) {
    return static_cast<uint32_t>(std::clamp(v / extent * kHilbertSide, 0.0, double(kHilbertSide - 1)));
  };
  for (uint32_t h = 0; h < g.halfedges.size(); ++h) {
    const uint32_t t = g.halfedges[h].twin;
    if (h > t || (!want[h] && !want[t])) continue;
    const glm::dvec2 mid = pointAt(g, g.halfedges[h], 0.5 * g.halfedges[h].length) - lo;
    streets.push_back({hilbertIndex(kHilbertSide, cellOf(mid.x), cellOf(mid.y)), h,
                       streetCost(g, h, want[h], want[t], opt)});
  }
  std::sort(streets.begin(), streets.end(),
            [](const Street& a, const Street& b) { return std::tie(a.d, a.h) < std::tie(b.d, b.h); });
  double total = 0;
  for (const Street& s : streets) total += s.cost;
  ShardPlan plan;
  plan.streets.resize(count);
  plan.cost.assign(count, 0.0);
  double before = 0;
  for (const Street& s : streets) {
    const double mid = before + 0.5 * s.cost;
    const uint32_t k = std::min(count - 1, static_cast<uint32_t>(mid / total * count));
    plan.streets[k].push_back(s.h);
    plan.cost[k] += s.cost;
    before += s.cost;
  }
  for (auto& v : plan.streets) std::sort(v.begin(), v.end());
  return plan;
}

}  // namespace blvd::bake
