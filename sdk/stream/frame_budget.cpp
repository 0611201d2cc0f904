#include "stream/frame_budget.h"

#include <algorithm>
#include <cmath>

namespace blvd::stream {
namespace {
constexpr double kForget = 0.9;   // history weight kept per frame (~10 frames)
constexpr double kMaxStep = 2.0;  // the budget changes by at most ×2 or ÷2 a frame
}  // namespace

PolygonBudget::PolygonBudget(double target_ms, uint64_t min_triangles, uint64_t max_triangles)
    : target_ms_(target_ms), min_(min_triangles), max_(std::max(min_triangles, max_triangles)), p_(max_) {}

uint64_t PolygonBudget::next(double frame_ms, uint64_t triangles) {
  if (!(frame_ms > 0) || !std::isfinite(frame_ms)) return p_;
  const double x = double(triangles), y = frame_ms;
  sw_ = sw_ * kForget + 1;
  sx_ = sx_ * kForget + x;
  sy_ = sy_ * kForget + y;
  sxx_ = sxx_ * kForget + x * x;
  sxy_ = sxy_ * kForget + x * y;
  const double mx = sx_ / sw_, my = sy_ / sw_;
  const double var = sxx_ / sw_ - mx * mx, cov = sxy_ / sw_ - mx * my;
  // The slope needs spread in the history; until then (or if the fit says
  // triangles are free) assume time is proportional to triangles.
  if (var > 1e-6 * (mx * mx + 1) && cov > 0) {
    per_tri_ms_ = cov / var;
    fixed_ms_ = std::max(0.0, my - per_tri_ms_ * mx);
  } else {
    per_tri_ms_ = mx > 0 ? my / mx : 0;
    fixed_ms_ = 0;
  }
  double want = double(p_);
  if (per_tri_ms_ > 0) want = (target_ms_ - fixed_ms_) / per_tri_ms_;
  else if (frame_ms < target_ms_) want = double(p_) * 2;
  unreachable_ = fixed_ms_ + per_tri_ms_ * double(min_) > target_ms_;
  // Damped: at most a factor kMaxStep per frame, so one noisy frame cannot
  // swing the picture.
  const double lo = double(std::max<uint64_t>(p_, 1)) / kMaxStep, hi = double(std::max<uint64_t>(p_, 1)) * kMaxStep;
  want = std::clamp(want, lo, hi);
  p_ = static_cast<uint64_t>(std::clamp(want, double(min_), double(max_)));
  return p_;
}

uint64_t shareBudget(uint64_t budget, const float* ach, const LodChain* chains, size_t n, uint32_t* order,
                     uint8_t* level) {
  double sum = 0;
  for (size_t i = 0; i < n; ++i) sum += std::max(0.0f, ach[i]);
  for (size_t i = 0; i < n; ++i) order[i] = static_cast<uint32_t>(i);
  std::sort(order, order + n, [&](uint32_t a, uint32_t b) { return ach[a] > ach[b] || (ach[a] == ach[b] && a < b); });
  double carry = 0;
  uint64_t total = 0;
  for (size_t k = 0; k < n; ++k) {
    const uint32_t i = order[k];
    const LodChain& c = chains[i];
    if (c.levels == 0) {
      level[i] = 0;
      continue;
    }
    const double share = (sum > 0 ? std::max(0.0f, ach[i]) / sum : 1.0 / double(n)) * double(budget) + carry;
    uint32_t best = 0;
    double best_d = std::fabs(double(c.triangles[0]) - share);
    for (uint32_t l = 1; l < c.levels; ++l) {
      const double d = std::fabs(double(c.triangles[l]) - share);
      if (d < best_d) best_d = d, best = l;
    }
    level[i] = static_cast<uint8_t>(best);
    total += c.triangles[best];
    // What this object did not use passes on; an overdraft is not charged.
    carry = std::max(0.0, share - double(c.triangles[best]));
  }
  return total;
}

}  // namespace blvd::stream
