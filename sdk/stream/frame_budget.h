// A frame-time budget shared by coverage ("Frame budget"), after
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
// Exponentially weighted least-squares line y ≈ a + b·x over recent samples.
// Until the history has spread in x (or when it finds y falling with x) it
// assumes y proportional to x, the safe guess for a cost. A lone sample far
// from the line is clipped (noise); two in a row on the same side rescale the
// history (a change of level).
class CostLine {
 public:
  void add(double x, double y);
  double intercept() const { return a_; }
  double slope() const { return b_; }
  void clear() { *this = CostLine(); }

 private:
  // Weighted sums (weight decays by kForget per sample).
  double sw_ = 0, sx_ = 0, sy_ = 0, sxx_ = 0, sxy_ = 0;
  double a_ = 0, b_ = 0;
  bool fitted_ = false;  // a_, b_ come from the regression, not the proportional guess
  int outlier_side_ = 0;      // the last sample was clipped: +1 from above, -1 from below
  double outlier_ratio_ = 1;  // and its ratio to the line
};

class PolygonBudget {
 public:
  // target_ms > 0; the budget stays within [min_triangles, max_triangles].
  PolygonBudget(double target_ms, uint64_t min_triangles, uint64_t max_triangles);

  // Feeds the last frame (its measured time and triangles drawn) and returns
  // the polygon budget P for the next frame.
  uint64_t next(double frame_ms, uint64_t triangles);

  uint64_t budget() const { return p_; }
  double target() const { return target_ms_; }
  // Moves the frame time aimed at (FrameBudget's tail margin); target_ms > 0.
  void setTarget(double target_ms) { target_ms_ = target_ms; }
  double fixedMs() const { return fixed_ms_; }          // the model's intercept
  double msPerTriangle() const { return per_tri_ms_; }  // the model's slope
  // True when even the smallest budget is predicted to miss the target.
  bool unreachable() const { return unreachable_; }
  // Forgets the history and starts again from budget p (after frames drawn
  // under another regime, e.g. at a reduced resolution, whose times would
  // mislead the fit).
  void restart(uint64_t p);

 private:
  double target_ms_;
  uint64_t min_, max_, p_;
  CostLine fit_;
  double fixed_ms_ = 0, per_tri_ms_ = 0;
  bool unreachable_ = false;
};

// The budget's second knob, for a fill-bound GPU (docs/decisions/0008; not in
// Marvie et al., whose frames were bound by polygons): once the polygon budget
// is spent (every visible block at its coarsest level) and the frame still
// misses the target, draw the view at fewer pixels and stretch it. Same
// history model as PolygonBudget, in pixels: frame ≈ fixed + per_pixel ×
// pixels. The scale moves by at most 1/16 a frame and in steps of
// 1/64, so the picture does not shimmer.
class RenderScale {
 public:
  // target_ms > 0; the scale stays within [min_scale, 1], min_scale in (0, 1].
  RenderScale(double target_ms, double min_scale);

  // Feeds the last frame (its time and the pixels it shaded, of
  // full_pixels at scale 1) and returns the scale for the next frame.
  double next(double frame_ms, uint64_t pixels, uint64_t full_pixels);

  double scale() const { return scale_; }
  double minScale() const { return min_; }
  void setTarget(double target_ms) { target_ms_ = target_ms; }
  // True when even min_scale is predicted to miss the target.
  bool unreachable() const { return unreachable_; }

 private:
  double target_ms_, min_, scale_ = 1.0;
  CostLine fit_;
  bool unreachable_ = false;
};

// Both knobs in their order: the polygon budget first (Marvie et al.), the
// render scale only once the polygons are spent (every visible block at its
// coarsest level) and the frame still misses the target; back to polygons,
// with a fresh history, when a frame at scale 1 fits again. With min_scale 1
// it is PolygonBudget alone.
//
// The tail margin (docs/decisions/0008 §6; not in Marvie et al.): frames
// scatter around the time the knobs aim for (a CPU shared with other work, a
// driver's flush), and for a display a late frame matters more than a median
// a little under the target. FrameBudget keeps the ratio of each of the last
// kTailWindow frames to the aim it was drawn under; when their 95th
// percentile would carry frames past kTailAim × target, it aims lower, by
// as much as that takes, but never below kMinAim × target, so the median
// stays within 8 % of the target and only the tail gives way. On a steady
// machine the aim is the target. kTailAim lies under the bound kTailLimit by
// about the sampling error of that 95th percentile: from 128 frames of a
// tail like JitteryMachine's (tests/runtime/test_frame_budget.cpp) it moves
// by 5.5 % (one standard deviation) from window to window, and aimed at the
// bound itself the frames' p95 came out over it (0008 §17).
class FrameBudget {
 public:
  static constexpr uint32_t kTailWindow = 128;
  static constexpr double kTailLimit = 1.25;  // p95 at most this × the target
  static constexpr double kTailAim = 1.20;    // where the tail is aimed: under the limit by its estimate's noise
  static constexpr double kMinAim = 0.92;     // the aim never goes below this × the target

  FrameBudget(double target_ms, uint64_t max_triangles, double min_scale);

  // Feeds the last frame: its time, the block triangles it drew, the fewest
  // its visible blocks could draw (all at their coarsest levels), and the
  // pixels it shaded of full_pixels at scale 1.
  void next(double frame_ms, uint64_t triangles, uint64_t floor_triangles, uint64_t pixels, uint64_t full_pixels);

  uint64_t polygonBudget() const { return poly_.budget(); }
  double scale() const { return fill_ ? scale_.scale() : 1.0; }
  bool fillMode() const { return fill_; }
  bool scalable() const { return scale_.minScale() < 1.0; }
  // True when the coarsest levels at the smallest scale are predicted to miss.
  bool unreachable() const { return fill_ ? scale_.unreachable() : poly_.unreachable() && !scalable(); }
  const PolygonBudget& polygons() const { return poly_; }
  double target() const { return target_ms_; }
  double aim() const { return aim_ms_; }  // the frame time the knobs aim for now

 private:
  void updateAim(double frame_ms);

  PolygonBudget poly_;
  RenderScale scale_;
  bool fill_ = false;
  double target_ms_, aim_ms_;
  float ratio_[kTailWindow] = {};  // frame time / aim, the last kTailWindow frames
  float scratch_[kTailWindow] = {};
  uint32_t ratios_ = 0, next_ratio_ = 0;
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
