// The far-city metrics; definitions in far_metrics.h.
#include "cli/far_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "cli/bench_util.h"
#include "imaging/metrics.h"

namespace blvd::cli {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// Felzenszwalb & Huttenlocher, "Distance Transforms of Sampled Functions",
// Theory of Computing 8 (2012), §2.1: the lower envelope of the parabolas
// rooted at f[q], for n samples with stride `stride` (in place).
void edt1d(float* f, int n, size_t stride, std::vector<float>& d, std::vector<int>& v, std::vector<float>& z) {
  d.resize(size_t(n));
  v.resize(size_t(n));
  z.resize(size_t(n) + 1);
  int k = -1;
  for (int q = 0; q < n; ++q) {
    const float fq = f[size_t(q) * stride];
    if (fq == kInf) continue;
    while (k >= 0) {
      const int p = v[size_t(k)];
      const float fp = f[size_t(p) * stride];
      const float s = ((fq + float(q) * q) - (fp + float(p) * p)) / (2.0f * float(q - p));
      if (s > z[size_t(k)]) {
        ++k;
        v[size_t(k)] = q;
        z[size_t(k)] = s;
        z[size_t(k) + 1] = kInf;
        break;
      }
      --k;
    }
    if (k < 0) {
      k = 0;
      v[0] = q;
      z[0] = -kInf;
      z[1] = kInf;
    }
  }
  if (k < 0) return;  // no finite sample: all stay +inf
  int j = 0;
  for (int q = 0; q < n; ++q) {
    while (z[size_t(j) + 1] < float(q)) ++j;
    const int p = v[size_t(j)];
    d[size_t(q)] = float(q - p) * float(q - p) + f[size_t(p) * stride];
  }
  for (int q = 0; q < n; ++q) f[size_t(q) * stride] = d[size_t(q)];
}

// Boundary pixels of a binary mask: set, with a 4-neighbour inside the image
// that is not set (the image border is not a silhouette).
std::vector<uint8_t> boundary(const std::vector<uint8_t>& m, int w, int h) {
  std::vector<uint8_t> b(m.size(), 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      if (!m[i]) continue;
      b[i] = (x > 0 && !m[i - 1]) || (x + 1 < w && !m[i + 1]) || (y > 0 && !m[i - size_t(w)]) ||
             (y + 1 < h && !m[i + size_t(w)]);
    }
  return b;
}

// Distances from every boundary pixel of `a` to the nearest of `b` (and the
// other way) appended to `out`, capped at `cap`.
void silhouetteDistances(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b, int w, int h, double cap,
                         std::vector<double>& out) {
  const std::vector<float> db = distanceTransform2(b, w, h);
  for (size_t i = 0; i < a.size(); ++i)
    if (a[i]) out.push_back(std::min(cap, std::sqrt(double(db[i]))));
}

// Along one row or column of `e` (n pixels, `stride` apart), each set
// pixel's run length, merged into `t` with `merge`.
template <class Merge>
void runLengths(const uint8_t* e, uint16_t* t, int n, size_t stride, Merge merge) {
  for (int k = 0; k < n;) {
    if (!e[size_t(k) * stride]) {
      ++k;
      continue;
    }
    int end = k;
    while (end < n && e[size_t(end) * stride]) ++end;
    for (int j = k; j < end; ++j) t[size_t(j) * stride] = merge(t[size_t(j) * stride], uint16_t(end - k));
    k = end;
  }
}

// Per pixel of `e` (set: far visibility wrong there), the shorter of the
// horizontal and vertical runs of `e` through it; 0 elsewhere.
std::vector<uint16_t> runThickness(const std::vector<uint8_t>& e, int w, int h) {
  std::vector<uint16_t> t(e.size(), 0);
  const auto first = [](uint16_t, uint16_t run) { return run; };
  const auto shorter = [](uint16_t had, uint16_t run) { return std::min(had, run); };
  for (int y = 0; y < h; ++y) runLengths(&e[size_t(y) * w], &t[size_t(y) * w], w, 1, first);
  for (int x = 0; x < w; ++x) runLengths(&e[size_t(x)], &t[size_t(x)], h, size_t(w), shorter);
  return t;
}

// The visibility error of each boundary pixel of `b`: the thickest wrong
// region at it or its 4-neighbours (0: the silhouettes agree there).
void boundaryThickness(const std::vector<uint8_t>& b, const std::vector<uint16_t>& t, int w, int h,
                       std::vector<double>& out) {
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      if (!b[i]) continue;
      uint16_t m = t[i];
      if (x > 0) m = std::max(m, t[i - 1]);
      if (x + 1 < w) m = std::max(m, t[i + 1]);
      if (y > 0) m = std::max(m, t[i - size_t(w)]);
      if (y + 1 < h) m = std::max(m, t[i + size_t(w)]);
      out.push_back(double(m));
    }
}

bool drawnFar(uint32_t id, const FarInputs& in) {
  if (id == 0) return false;
  if (id & kItemImpostor) return true;
  return !in.is_local(id - 1);
}

// Does test id `t` stand for far block `b` (its impostor layer, or itself)?
bool standsFor(uint32_t t, uint32_t b, const FarInputs& in) {
  if (t == 0) return false;
  if (t & kItemImpostor) return in.layer_holds && (t & ~kItemImpostor) >= 1 && in.layer_holds((t & ~kItemImpostor) - 1, b);
  return t - 1 == b;
}

// Counts one pixel of far block `b` by what test id `t` shows there.
void tally(MissingObject& o, uint32_t t, uint32_t b, const FarInputs& in) {
  o.block = b;
  ++o.px;
  if (standsFor(t, b, in)) ++o.own;
  else if (t == 0) ++o.nothing;
  else if (t & kItemImpostor) ++o.other_layer;
  else ++o.geometry;
}

}  // namespace

std::vector<float> distanceTransform2(const std::vector<uint8_t>& seed, int w, int h) {
  std::vector<float> f(seed.size());
  for (size_t i = 0; i < seed.size(); ++i) f[i] = seed[i] ? 0.0f : kInf;
  std::vector<float> d, z;
  std::vector<int> v;
  for (int y = 0; y < h; ++y) edt1d(&f[size_t(y) * w], w, 1, d, v, z);
  for (int x = 0; x < w; ++x) edt1d(&f[size_t(x)], h, size_t(w), d, v, z);
  return f;
}

FarMetrics measureFar(const FarInputs& in) {
  FarMetrics m;
  const size_t n = size_t(in.w) * in.h;
  if (n == 0) return m;
  std::vector<uint8_t> F(n, 0), D(n, 0), bad(n, 0);
  for (size_t i = 0; i < n; ++i) {
    const uint32_t r = in.ref_items[i];
    F[i] = r != 0 && !(r & kItemImpostor) && !in.is_local(r - 1);
    D[i] = drawnFar(in.test_items[i], in);
    bad[i] = imaging::pixelError(in.ref_rgba + 4 * i, in.test_rgba + 4 * i) > in.threshold;
  }
  // Spurious pixels lie farther than the tolerance from F.
  const std::vector<float> dF = distanceTransform2(F, in.w, in.h);
  const float tol2 = float(in.edge_tolerance_px) * float(in.edge_tolerance_px);
  m.classes.assign(n, 0);
  uint64_t far_bad = 0, holes = 0, spurious = 0;
  std::unordered_map<uint32_t, MissingObject> objects;  // far block -> what shows on its pixels
  for (size_t i = 0; i < n; ++i) {
    if (F[i]) {
      ++m.far_px;
      const bool hole = !D[i];
      far_bad += bad[i];
      holes += hole;
      m.classes[i] = (bad[i] || hole) ? 2 : 1;
      MissingObject& o = objects[in.ref_items[i] - 1];
      tally(o, in.test_items[i], in.ref_items[i] - 1, in);
      o.bad += bad[i];
    } else if (D[i] && bad[i] && dF[i] > tol2) {
      ++spurious;
      m.classes[i] = 3;
    }
  }
  m.far_bad = m.far_px ? double(far_bad) / double(m.far_px) : 0.0;
  m.holes = double(holes) / double(n);
  m.spurious = double(spurious) / double(n);
  for (const auto& [b, o] : objects)
    if (o.px >= in.min_object_px && 2 * o.own < o.px) m.missing_shown.push_back(o);
  std::sort(m.missing_shown.begin(), m.missing_shown.end(),
            [](const MissingObject& a, const MissingObject& b) { return a.block < b.block; });
  for (const MissingObject& o : m.missing_shown) m.missing.push_back(o.block);
  m.missing_objects = uint32_t(m.missing.size());

  const std::vector<uint8_t> bF = boundary(F, in.w, in.h), bD = boundary(D, in.w, in.h);
  for (uint8_t b : bF) m.silhouette_px += b;
  const double diag = std::sqrt(double(in.w) * in.w + double(in.h) * in.h);
  std::vector<double> dist;
  silhouetteDistances(bF, bD, in.w, in.h, diag, dist);
  silhouetteDistances(bD, bF, in.w, in.h, diag, dist);
  m.silhouette_distance_px = dist.empty() ? 0.0 : pct(std::move(dist), 95.0);
  std::vector<uint8_t> E(n);
  for (size_t i = 0; i < n; ++i) E[i] = F[i] != D[i];
  const std::vector<uint16_t> thick = runThickness(E, in.w, in.h);
  std::vector<double> err;
  boundaryThickness(bF, thick, in.w, in.h, err);
  boundaryThickness(bD, thick, in.w, in.h, err);
  m.visibility_error_px = err.empty() ? 0.0 : pct(std::move(err), 95.0);
  return m;
}

void farOverlay(const uint8_t* ref_rgba, const FarMetrics& m, int w, int h, uint8_t* out) {
  const size_t n = size_t(w) * h;
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* p = ref_rgba + 4 * i;
    const double y = 0.6 * (0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2]);
    uint8_t* o = out + 4 * i;
    double r = y, g = y, b = y;
    switch (i < m.classes.size() ? m.classes[i] : 0) {
      case 1: r = 0.6 * y, g = 0.6 * y + 30, b = 0.6 * y + 110; break;  // far, fine: blue tint
      case 2: r = 230, g = 30, b = 30; break;                            // far, wrong or a hole
      case 3: r = 230, g = 0, b = 230; break;                            // spurious
      default: break;
    }
    o[0] = uint8_t(std::min(255.0, r));
    o[1] = uint8_t(std::min(255.0, g));
    o[2] = uint8_t(std::min(255.0, b));
    o[3] = 255;
  }
}

}  // namespace blvd::cli
