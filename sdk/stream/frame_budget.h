// A frame-time budget shared by coverage (issue 4, "Frame budget"), after
// Marvie, Perret and Bouatouch, "Remote Interactive Walkthrough of City
// Models" (seed 004), panel "Using LODs and ACHs to match a target frame
// rate":
//   1. "Analyze frame rate history, analyze polygon budget history, deduce a
//      polygon budget for the new frame" -> PolygonBudget::next().
//   2. "Renormalize ACH values of objects that are found to be visible", then
//      "the polygon budget P is shared by the visible objects P_i = ACH_i · P";
//      "each LOD node i selects its level of detail whose polygon count is
//      nearest to P_i" and "the portion of P_i that is not used for the level
//      is given up to the next LOD node" -> shareBudget().
// Pure and allocation-free: the runtime calls both every frame.
#pragma once
#include <cstddef>
#include <cstdint>

namespace blvd::stream {

// The history model: frame time ≈ fixed + per_triangle × triangles, fitted
// by exponentially weighted least squares over recent frames (a frame's fill
// and sky cost is the `fixed` part, which no polygon budget can remove).
class PolygonBudget {
 public:
  // target_ms > 0; the budget stays within [min_triangles, max_triangles].
  PolygonBudget(double target_ms, uint64_t min_triangles, uint64_t max_triangles);

  // Feeds the last frame (its measured time and triangles drawn) and returns
  // the polygon budget P for the next frame.
  uint64_t next(double frame_ms, uint64_t triangles);

  uint64_t budget() const { return p_; }
  double target() const { return target_ms_; }
  double fixedMs() const { return fixed_ms_; }          // the model's intercept
  double msPerTriangle() const { return per_tri_ms_; }  // the model's slope
  // True when even the smallest budget is predicted to miss the target.
  bool unreachable() const { return unreachable_; }

 private:
  double target_ms_;
  uint64_t min_, max_, p_;
  // Weighted sums for the fit (weight decays by kForget per frame).
  double sw_ = 0, sx_ = 0, sy_ = 0, sxx_ = 0, sxy_ = 0;
  double fixed_ms_ = 0, per_tri_ms_ = 0;
  bool unreachable_ = false;
};

// One object's LOD chain: triangles per level, finest first.
struct LodChain {
  const uint32_t* triangles = nullptr;
  uint32_t levels = 0;
};

// Shares `budget` over `n` visible objects with coverage `ach` (renormalised
// here to sum to 1; all-zero coverage shares equally). Objects are served in
// decreasing coverage; each takes the level whose triangle count is nearest
// its share plus what the previous objects left, and passes on what it did
// not use. `order` is scratch of n entries. Writes the level per object to
// `level` and returns the triangles chosen in all.
uint64_t shareBudget(uint64_t budget, const float* ach, const LodChain* chains, size_t n, uint32_t* order,
                     uint8_t* level);

}  // namespace blvd::stream
