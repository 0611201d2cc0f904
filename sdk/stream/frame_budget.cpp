#include "stream/frame_budget.h"

#include <algorithm>
#include <cmath>

namespace blvd::stream {
namespace {
constexpr double kForget = 0.9;   // history weight kept per frame (~10 frames)
constexpr double kMaxStep = 2.0;  // the budget changes by at most ×2 or ÷2 a frame
// The render scale rises by at most 1/16 a frame (no shimmer while it
// climbs back) but may fall by up to 1/4: a frame far over the aim is a late
// frame on screen, and at 1/16 a frame, going from 1 to 0.69 took five frames
// over the target in a row, three of them by more than 1.25 times (blvd
// bench budget, docs/decisions/0008 §8). Dynamic resolution in games does the
// same: drop fast, recover slowly.
constexpr double kMaxScaleStep = 0.0625;
constexpr double kMaxScaleDrop = 0.25;
// Robust fit: once the line has history, a sample is taken as at most kClip
// times (or 1/kClip of) what the line predicts (Huber's M-estimation, the
// residual clipped: Huber 1964). A frame delayed by something other than its
// triangles and pixels (a CPU shared with other work) then moves the line by
// little, so the knobs do not chase noise; a real change in cost still gets
// through, kClip a frame.
constexpr double kClip = 1.15;
constexpr double kRobustAfter = 4.0;  // weighted samples before clipping starts
}  // namespace

void CostLine::add(double x, double y) {
  if (fitted_ && sw_ >= kRobustAfter) {  // not against the proportional guess
    const double predicted = a_ + b_ * x;
    if (predicted > 0) {
      // A second sample in a row past the clip on the same side is not
      // noise but a change of level (another process took or gave back the
      // CPU): every cost is taken as r times what the history says, r the
      // two samples' geometric mean ratio to the line, so slope and
      // intercept scale together and the fit keeps its spread.
      const double ratio = y / predicted;
      const int side = ratio > kClip ? 1 : ratio < 1 / kClip ? -1 : 0;
      if (side != 0 && side == outlier_side_) {
        const double r = std::sqrt(ratio * outlier_ratio_);
        sy_ *= r;  // the line below is refitted from these
        sxy_ *= r;
        outlier_side_ = 0;
      } else {
        outlier_side_ = side;
        outlier_ratio_ = ratio;
        y = std::clamp(y, predicted / kClip, predicted * kClip);
      }
    }
  }
  sw_ = sw_ * kForget + 1;
  sx_ = sx_ * kForget + x;
  sy_ = sy_ * kForget + y;
  sxx_ = sxx_ * kForget + x * x;
  sxy_ = sxy_ * kForget + x * y;
  const double mx = sx_ / sw_, my = sy_ / sw_;
  const double var = sxx_ / sw_ - mx * mx, cov = sxy_ / sw_ - mx * my;
  // The slope needs spread in the history; until then (or if the fit says
  // x is free) assume y is proportional to x.
  fitted_ = var > 1e-6 * (mx * mx + 1) && cov > 0;
  if (fitted_) {
    b_ = cov / var;
    a_ = std::max(0.0, my - b_ * mx);
  } else {
    b_ = mx > 0 ? my / mx : 0;
    a_ = 0;
  }
}

PolygonBudget::PolygonBudget(double target_ms, uint64_t min_triangles, uint64_t max_triangles)
    : target_ms_(target_ms), min_(min_triangles), max_(std::max(min_triangles, max_triangles)), p_(max_) {}

void PolygonBudget::restart(uint64_t p) {
  fit_.clear();
  fixed_ms_ = per_tri_ms_ = 0;
  unreachable_ = false;
  p_ = std::clamp(p, min_, max_);
}

uint64_t PolygonBudget::next(double frame_ms, uint64_t triangles) {
  if (!(frame_ms > 0) || !std::isfinite(frame_ms)) return p_;
  fit_.add(double(triangles), frame_ms);
  per_tri_ms_ = fit_.slope();
  fixed_ms_ = fit_.intercept();
  double want = double(p_);
  if (per_tri_ms_ > 0) want = (target_ms_ - fixed_ms_) / per_tri_ms_;
  else if (frame_ms < target_ms_) want = double(p_) * 2;
  // The fewest triangles a frame can draw: min_, or more where the frame
  // drew more than its budget (every visible block at its coarsest level).
  const uint64_t least = triangles > p_ ? triangles : min_;
  unreachable_ = fixed_ms_ + per_tri_ms_ * double(least) > target_ms_;
  // Damped: at most a factor kMaxStep per frame, so one noisy frame cannot
  // swing the picture. Upwards also at most kMaxStep times what the frame
  // drew: the line was fitted on the triangle counts drawn, and far beyond
  // them it is an extrapolation. A budget the scene did not use (a cell with
  // little geometry) would otherwise climb unchecked, and the next cell, whose
  // triangles may cost more each (nearer, larger on screen), would take all
  // of it in its first frame (docs/decisions/0008 §8).
  const double lo = double(std::max<uint64_t>(p_, 1)) / kMaxStep, hi = double(std::max<uint64_t>(p_, 1)) * kMaxStep;
  want = std::min(std::clamp(want, lo, hi), double(std::max<uint64_t>(triangles, 1)) * kMaxStep);
  p_ = static_cast<uint64_t>(std::clamp(want, double(min_), double(max_)));
  return p_;
}

RenderScale::RenderScale(double target_ms, double min_scale)
    : target_ms_(target_ms), min_(std::clamp(min_scale, 1.0 / 64, 1.0)) {}

double RenderScale::next(double frame_ms, uint64_t pixels, uint64_t full_pixels) {
  if (!(frame_ms > 0) || !std::isfinite(frame_ms) || pixels == 0 || full_pixels == 0) return scale_;
  fit_.add(double(pixels), frame_ms);
  const double fixed = fit_.intercept(), per_px = fit_.slope();
  const double full = double(full_pixels);
  double want = scale_;
  if (per_px > 0) want = std::sqrt(std::max(0.0, (target_ms_ - fixed) / per_px) / full);
  else if (frame_ms < target_ms_) want = scale_ + kMaxScaleStep;
  unreachable_ = fixed + per_px * full * min_ * min_ > target_ms_;
  want = std::clamp(want, scale_ - kMaxScaleDrop, scale_ + kMaxScaleStep);
  want = std::round(want * 64.0) / 64.0;
  scale_ = std::clamp(want, min_, 1.0);
  return scale_;
}

FrameBudget::FrameBudget(double target_ms, uint64_t max_triangles, double min_scale)
    : poly_(target_ms, 0, max_triangles), scale_(target_ms, min_scale), target_ms_(target_ms), aim_ms_(target_ms) {}

void FrameBudget::updateAim(double frame_ms) {
  ratio_[next_ratio_] = float(frame_ms / aim_ms_);
  next_ratio_ = (next_ratio_ + 1) % kTailWindow;
  ratios_ = std::min(ratios_ + 1, kTailWindow);
  if (ratios_ < kTailWindow / 4) return;  // too few frames to tell a tail
  std::copy(ratio_, ratio_ + ratios_, scratch_);
  float* q = scratch_ + size_t(0.95 * double(ratios_ - 1));
  std::nth_element(scratch_, q, scratch_ + ratios_);
  aim_ms_ = target_ms_ * std::clamp(kTailAim / double(*q), kMinAim, 1.0);
  poly_.setTarget(aim_ms_);
  scale_.setTarget(aim_ms_);
}

void FrameBudget::next(double frame_ms, uint64_t triangles, uint64_t floor_triangles, uint64_t pixels,
                       uint64_t full_pixels) {
  if (!(frame_ms > 0) || !std::isfinite(frame_ms)) return;
  updateAim(frame_ms);
  const double target = aim_ms_;
  if (scalable() && !fill_ && poly_.budget() <= floor_triangles && frame_ms > target) fill_ = true;
  if (!fill_) {
    poly_.next(frame_ms, triangles);
    return;
  }
  if (pixels >= full_pixels && frame_ms <= target) {
    // A whole-resolution frame fits: polygons again, from the floor up.
    fill_ = false;
    poly_.restart(floor_triangles);
    return;
  }
  scale_.next(frame_ms, pixels, full_pixels);
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
