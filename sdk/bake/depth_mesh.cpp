// Textured depth mesh of one captured layer (Sillion, Drettakis, Bodelet 1997,
// §4.2 "Identification of important features" and "Triangulation and 3D
// reprojection"); see depth_mesh.h for the contract.
//
// Image frame used throughout: continuous pixels, x right, y DOWN, pixel (u, v)
// covering [u, u+1] x [v, v+1]. The triangulation itself runs in (x, -y) so
// that triangulateSegments' counter-clockwise output is counter-clockwise on
// screen (right, up), which is counter-clockwise as seen from the camera.
#include "bake/depth_mesh.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <numeric>
#include <utility>

#include <glm/geometric.hpp>

#include "bake/plane_geometry.h"

namespace blvd::bake {

glm::dvec3 PinholeCamera::ray(double x, double y) const {
  const double sx = (2.0 * x / width - 1.0) * tan_half_x;
  const double sy = (1.0 - 2.0 * y / height) * tan_half_y;
  return forward + right * sx + up * sy;
}

bool PinholeCamera::project(const glm::dvec3& world, glm::dvec2& image, double& depth) const {
  const glm::dvec3 d = world - eye;
  depth = glm::dot(d, forward);
  if (!(depth > 0.0)) return false;
  const double sx = glm::dot(d, right) / (depth * tan_half_x);
  const double sy = glm::dot(d, up) / (depth * tan_half_y);
  image = glm::dvec2((sx + 1.0) * 0.5 * width, (1.0 - sy) * 0.5 * height);
  return true;
}

namespace {

using Polyline = std::vector<glm::dvec2>;

// The 8 neighbour offsets; the first four are the 4-neighbours.
constexpr std::array<int, 8> kDx = {1, 0, -1, 0, 1, -1, -1, 1};
constexpr std::array<int, 8> kDy = {0, 1, 0, -1, 1, 1, -1, -1};

// Relative difference of two depths given as inverse depths:
// |z_a - z_b| / min(z_a, z_b) == |w_a - w_b| / min(w_a, w_b) with w = 1/z.
double relInv(double wa, double wb) {
  const double lo = std::min(wa, wb);
  if (!(lo > 0.0)) return std::numeric_limits<double>::infinity();
  return std::abs(wa - wb) / lo;
}

// Per-pixel data shared by the steps.
struct Image {
  int w = 0, h = 0;
  std::vector<uint8_t> cov;  // 1 = covered (geometry with a usable depth)
  std::vector<double> inv;   // 1 / z where covered, else 0

  bool in(int x, int y) const { return x >= 0 && y >= 0 && x < w && y < h; }
  size_t at(int x, int y) const { return static_cast<size_t>(y) * static_cast<size_t>(w) + x; }
  bool covered(int x, int y) const { return in(x, y) && cov[at(x, y)] != 0; }
  // A covered pixel with a background or off-image 8-neighbour: it lies on
  // the external contour.
  bool onContour(int x, int y) const {
    for (int k = 0; k < 8; ++k)
      if (!covered(x + kDx[k], y + kDy[k])) return true;
    return false;
  }
};

// ---------------------------------------------------------------------------
// Polyline simplification (Douglas-Peucker), iterative so long contours cannot
// exhaust the stack.

Polyline simplifyOpen(const Polyline& pts, double tol) {
  if (pts.size() <= 2) return pts;
  std::vector<uint8_t> keep(pts.size(), 0);
  keep.front() = keep.back() = 1;
  std::vector<std::pair<size_t, size_t>> stack{{0, pts.size() - 1}};
  while (!stack.empty()) {
    auto [i, j] = stack.back();
    stack.pop_back();
    double best = -1.0;
    size_t bi = i;
    for (size_t k = i + 1; k < j; ++k) {
      const double d = pointSegmentDistance(pts[k], pts[i], pts[j]);
      if (d > best) {
        best = d;
        bi = k;
      }
    }
    if (best > tol) {
      keep[bi] = 1;
      stack.push_back({i, bi});
      stack.push_back({bi, j});
    }
  }
  Polyline out;
  for (size_t k = 0; k < pts.size(); ++k)
    if (keep[k]) out.push_back(pts[k]);
  return out;
}

// A closed loop is split at its first point and the point farthest from it,
// and each half simplified. A loop that would collapse below a triangle (a
// one-pixel island) is kept as traced.
Polyline simplifyClosed(const Polyline& loop, double tol) {
  if (loop.size() <= 4) return loop;
  size_t far = 0;
  double best = -1.0;
  for (size_t k = 1; k < loop.size(); ++k) {
    const double d = glm::length(loop[k] - loop[0]);
    if (d > best) {
      best = d;
      far = k;
    }
  }
  Polyline a(loop.begin(), loop.begin() + static_cast<std::ptrdiff_t>(far) + 1);
  Polyline b(loop.begin() + static_cast<std::ptrdiff_t>(far), loop.end());
  b.push_back(loop[0]);
  Polyline sa = simplifyOpen(a, tol), sb = simplifyOpen(b, tol);
  Polyline out(sa.begin(), sa.end() - 1);           // drop `far`, it starts sb
  out.insert(out.end(), sb.begin(), sb.end() - 1);  // drop loop[0], it starts sa
  if (out.size() < 3) return loop;
  return out;
}

// ---------------------------------------------------------------------------
// Step 1 (S97 §4.2 "external contour"): the boundary of the union of covered
// pixel squares, traced along pixel edges ("cracks"), so that before
// simplification the contour encloses exactly the covered pixels. Each
// boundary edge is directed with the covered pixel on its right (on screen,
// y down); loops are followed turning right first, so pixels that touch only
// at a corner get separate loops (4-connected regions) and every loop is
// simple. Holes come out as loops of their own: the inside test is even-odd.
std::vector<Polyline> traceContours(const Image& im) {
  const int w = im.w, h = im.h;
  const size_t vw = static_cast<size_t>(w) + 1;
  auto vid = [&](int i, int j) { return static_cast<size_t>(j) * vw + static_cast<size_t>(i); };
  // Bit d set: an unused boundary edge leaves the vertex in direction d
  // (0 = +x, 1 = +y, 2 = -x, 3 = -y).
  std::vector<uint8_t> out(vw * (static_cast<size_t>(h) + 1), 0);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (!im.covered(x, y)) continue;
      if (!im.covered(x, y - 1)) out[vid(x, y)] |= 1;
      if (!im.covered(x + 1, y)) out[vid(x + 1, y)] |= 2;
      if (!im.covered(x, y + 1)) out[vid(x + 1, y + 1)] |= 4;
      if (!im.covered(x - 1, y)) out[vid(x, y + 1)] |= 8;
    }
  }
  std::vector<Polyline> loops;
  for (int j = 0; j <= h; ++j) {
    for (int i = 0; i <= w; ++i) {
      while (out[vid(i, j)] != 0) {
        const uint8_t bits = out[vid(i, j)];
        int d0 = 0;
        while (!(bits & (1 << d0))) ++d0;
        Polyline loop;
        int ci = i, cj = j, d = d0, prev = -1;
        for (;;) {
          out[vid(ci, cj)] &= static_cast<uint8_t>(~(1 << d));
          if (d != prev) loop.emplace_back(ci, cj);
          prev = d;
          ci += kDx[static_cast<size_t>(d)];
          cj += kDy[static_cast<size_t>(d)];
          // Right turn, straight on, left turn. The start edge counts as
          // available so the loop closes where it began.
          int next = -1;
          bool closed = false;
          for (int turn : {1, 0, 3}) {
            const int c = (d + turn) & 3;
            if (ci == i && cj == j && c == d0) {
              closed = true;
              break;
            }
            if (out[vid(ci, cj)] & (1 << c)) {
              next = c;
              break;
            }
          }
          if (closed || next < 0) break;  // next < 0 cannot happen: boundaries are closed
          d = next;
        }
        // The start is not a corner when the loop ends heading the way it began.
        if (prev == d0 && loop.size() > 1) loop.erase(loop.begin());
        if (loop.size() >= 3) loops.push_back(std::move(loop));
      }
    }
  }
  return loops;
}

// Even-odd inside test against the simplified contour loops, bucketed by
// pixel row. This is "inside the external contour" in the paper's sense; it
// also keeps the thin slivers between a simplified edge and the pixel
// staircase it replaced, which a test of the pixel under a centroid would
// punch out.
class ContourParity {
 public:
  ContourParity(const std::vector<Polyline>& loops, int height) : rows_(static_cast<size_t>(height)) {
    for (const Polyline& l : loops) {
      for (size_t k = 0; k < l.size(); ++k) {
        const glm::dvec2 a = l[k], b = l[(k + 1) % l.size()];
        if (a.y == b.y) continue;  // horizontal edges never cross a horizontal ray
        const size_t id = segs_.size();
        segs_.push_back({a, b});
        const int r0 = std::max(0, static_cast<int>(std::floor(std::min(a.y, b.y))));
        const int r1 = std::min(height - 1, static_cast<int>(std::floor(std::max(a.y, b.y))));
        for (int r = r0; r <= r1; ++r) rows_[static_cast<size_t>(r)].push_back(id);
      }
    }
  }
  bool inside(glm::dvec2 p) const {
    if (!(p.y >= 0.0) || p.y >= static_cast<double>(rows_.size())) return false;
    bool in = false;
    for (size_t id : rows_[static_cast<size_t>(p.y)]) {
      const glm::dvec2 a = segs_[id].a, b = segs_[id].b;
      if ((a.y > p.y) == (b.y > p.y)) continue;
      const double x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
      if (x > p.x) in = !in;
    }
    return in;
  }

 private:
  std::vector<Segment2> segs_;
  std::vector<std::vector<size_t>> rows_;
};

// ---------------------------------------------------------------------------
// Step 2 (S97 §4.2 "depth discrepancy image"). The discrepancy of a pair of
// covered 8-neighbours p, q is their relative depth difference (see
// DepthMeshOptions for why relative). Both pixels of a depth step would score
// the same, which gives two parallel chains per step; the paper wants one
// line per step, so the pair's score goes to the NEARER pixel only: the line
// then follows the silhouette of the occluder, which is where the step is.
// Background neighbours score nothing: that boundary is the contour's.
struct Discrepancy {
  std::vector<float> d;                       // per pixel, 0 where nothing exceeds anything
  std::vector<std::array<int8_t, 2>> toward;  // unit-ish step toward the far side
};

// Discrepancy of the pair (p, q = p + offset k), both covered. With planar
// prediction, 1/z is affine along a plane's image: each side is extrapolated
// one pixel across the pair and the smallest disagreement kept. A true step
// disagrees with every prediction; a slanted plane (even ground at grazing
// angles, whose rows differ by tens of percent) with none.
double pairDiscrepancy(const Image& im, int x, int y, size_t k, bool predict) {
  const int qx = x + kDx[k], qy = y + kDy[k];
  const double wp = im.inv[im.at(x, y)], wq = im.inv[im.at(qx, qy)];
  double s = relInv(wp, wq);
  if (predict) {
    const int bx = x - kDx[k], by = y - kDy[k];
    if (im.covered(bx, by)) s = std::min(s, relInv(2.0 * wp - im.inv[im.at(bx, by)], wq));
    const int fx = qx + kDx[k], fy = qy + kDy[k];
    if (im.covered(fx, fy)) s = std::min(s, relInv(2.0 * wq - im.inv[im.at(fx, fy)], wp));
  }
  return s;
}

Discrepancy discrepancyImage(const Image& im, const DepthMeshOptions& opt) {
  Discrepancy out;
  const size_t n = im.cov.size();
  out.d.assign(n, 0.0f);
  out.toward.assign(n, {0, 0});
  const double thr = opt.discrepancy_threshold;
  for (int y = 0; y < im.h; ++y) {
    for (int x = 0; x < im.w; ++x) {
      const size_t p = im.at(x, y);
      if (!im.cov[p]) continue;
      const double wp = im.inv[p];
      double best = 0.0;
      int bestK = -1, sx = 0, sy = 0;
      for (size_t k = 0; k < 8; ++k) {
        const int qx = x + kDx[k], qy = y + kDy[k];
        if (!im.covered(qx, qy)) continue;
        const double wq = im.inv[im.at(qx, qy)];
        if (!(wq < wp)) continue;  // q is not farther: the pair scores at q
        double s = relInv(wp, wq);
        if (opt.planar_prediction && s > thr) s = pairDiscrepancy(im, x, y, k, true);
        if (s > best) {
          best = s;
          bestK = static_cast<int>(k);
        }
        if (k < 4 && s > thr) {
          sx += kDx[k];
          sy += kDy[k];
        }
      }
      if (bestK < 0) continue;
      out.d[p] = static_cast<float>(std::min(best, 1e30));
      if (sx == 0 && sy == 0 && best > thr) {  // only a diagonal neighbour is far
        sx = kDx[static_cast<size_t>(bestK)];
        sy = kDy[static_cast<size_t>(bestK)];
      }
      out.toward[p] = {static_cast<int8_t>(std::clamp(sx, -1, 1)),
                       static_cast<int8_t>(std::clamp(sy, -1, 1))};
    }
  }
  return out;
}

// The paper's iterative extraction: "1. Find pixel with largest discrepancy.
// 2. Follow chain of pixels until we are blocked by the external contour or
// the discrepancy falls below the threshold. 3. Compute a polygonal
// approximation of the chain." Repeated until no unused pixel is above the
// threshold. Each chain pixel stands for the step edge half a pixel toward
// its far neighbours (the crack between the two surfaces). After a chain, its
// pixels' neighbours are retired so a 2-pixel-thick ridge (slanted steps)
// does not yield a second, parallel line.
std::vector<Polyline> extractChains(const Image& im, const Discrepancy& dis, const DepthMeshOptions& opt,
                                    size_t& keptChains) {
  const float thr = static_cast<float>(opt.discrepancy_threshold);
  std::vector<size_t> cand;
  for (size_t p = 0; p < dis.d.size(); ++p)
    if (dis.d[p] > thr) cand.push_back(p);
  std::stable_sort(cand.begin(), cand.end(), [&](size_t a, size_t b) { return dis.d[a] > dis.d[b]; });

  enum : uint8_t { kFree = 0, kUsed = 1, kRetired = 2 };
  std::vector<uint8_t> state(dis.d.size(), kFree);
  std::vector<uint32_t> stamp(dis.d.size(), 0);  // chain id + 1 of the chain holding a pixel
  std::vector<Polyline> lines;
  uint32_t chainId = 0;
  keptChains = 0;

  auto xy = [&](size_t p) {
    return std::pair<int, int>(static_cast<int>(p % static_cast<size_t>(im.w)),
                               static_cast<int>(p / static_cast<size_t>(im.w)));
  };

  // Extends `chain` from its back, given the direction it arrived from.
  // `exempt` (the other half's first step) may be touched by the first step.
  auto follow = [&](std::vector<size_t>& chain, glm::dvec2 dir, size_t exempt) {
    while (true) {
      const size_t cur = chain.back();
      const size_t prev = chain.size() >= 2 ? chain[chain.size() - 2] : cur;
      auto [cx, cy] = xy(cur);
      if (chain.size() > 1 && im.onContour(cx, cy)) return;  // blocked by the contour
      double bestScore = -std::numeric_limits<double>::infinity();
      size_t best = cur;
      glm::dvec2 bestStep(0.0);
      for (size_t k = 0; k < 8; ++k) {
        const int qx = cx + kDx[k], qy = cy + kDy[k];
        if (!im.in(qx, qy)) continue;
        const size_t q = im.at(qx, qy);
        if (state[q] != kFree || !(dis.d[q] > thr)) continue;
        // Never touch the chain's own earlier pixels: that would fold it back.
        bool touches = false;
        for (size_t m = 0; m < 8 && !touches; ++m) {
          const int rx = qx + kDx[m], ry = qy + kDy[m];
          if (!im.in(rx, ry)) continue;
          const size_t r = im.at(rx, ry);
          touches = stamp[r] == chainId + 1 && r != cur && r != prev && !(chain.size() == 1 && r == exempt);
        }
        if (touches) continue;
        const glm::dvec2 step = glm::normalize(glm::dvec2(kDx[k], kDy[k]));
        double score;
        if (dir == glm::dvec2(0.0)) {
          score = dis.d[q];
        } else {
          const double c = glm::dot(step, dir);
          if (c < -1e-9) continue;  // no turning back
          score = c + 0.01 * std::min(1.0, static_cast<double>(dis.d[q]));
        }
        if (score > bestScore) {
          bestScore = score;
          best = q;
          bestStep = step;
        }
      }
      if (best == cur) return;  // the discrepancy fell below the threshold
      state[best] = kUsed;
      stamp[best] = chainId + 1;
      chain.push_back(best);
      dir = dir == glm::dvec2(0.0) ? bestStep : glm::normalize(dir + bestStep);
    }
  };

  for (size_t s : cand) {
    if (state[s] != kFree) continue;
    state[s] = kUsed;
    stamp[s] = chainId + 1;
    std::vector<size_t> fwd{s};
    follow(fwd, glm::dvec2(0.0), s);
    std::vector<size_t> bwd{s};
    if (fwd.size() >= 2) {
      auto [ax, ay] = xy(fwd[0]);
      auto [bx, by] = xy(fwd[1]);
      follow(bwd, -glm::normalize(glm::dvec2(bx - ax, by - ay)), fwd[1]);
    }
    std::vector<size_t> chain(bwd.rbegin(), bwd.rend());
    chain.insert(chain.end(), fwd.begin() + 1, fwd.end());
    for (size_t p : chain) {
      auto [px, py] = xy(p);
      for (size_t k = 0; k < 8; ++k) {
        const int qx = px + kDx[k], qy = py + kDy[k];
        if (im.in(qx, qy) && state[im.at(qx, qy)] == kFree) state[im.at(qx, qy)] = kRetired;
      }
    }
    ++chainId;
    if (static_cast<int>(chain.size()) < std::max(2, opt.min_chain_px)) continue;
    Polyline pts;
    pts.reserve(chain.size());
    for (size_t p : chain) {
      auto [px, py] = xy(p);
      const auto t = dis.toward[p];
      pts.emplace_back(px + 0.5 + 0.5 * t[0], py + 0.5 + 0.5 * t[1]);
    }
    Polyline simple = simplifyOpen(pts, opt.line_tolerance_px);
    if (simple.size() >= 2 && simple.front() != simple.back()) {
      lines.push_back(std::move(simple));
      ++keptChains;
    }
  }
  return lines;
}

// Uniform buckets over segments for "which segments pass within r of p":
// snapping and grid clearance would otherwise cost (points x segments),
// which noisy depth (thousands of short chains) turns into seconds.
class SegmentGrid {
 public:
  struct Item {
    Segment2 seg;
    int owner;  // -1: contour; else the discrepancy line's index
    int k;      // segment index within its polyline
  };

  SegmentGrid(int w, int h, double cell)
      : cell_(cell),
        nx_(static_cast<int>(w / cell) + 1),
        ny_(static_cast<int>(h / cell) + 1),
        cells_(static_cast<size_t>(nx_) * static_cast<size_t>(ny_)) {}

  void add(const Segment2& seg, int owner, int k) {
    const uint32_t id = static_cast<uint32_t>(items_.size());
    items_.push_back({seg, owner, k});
    mark_.push_back(0);
    int x0, y0, x1, y1;
    range(std::min(seg.a.x, seg.b.x), std::min(seg.a.y, seg.b.y), std::max(seg.a.x, seg.b.x),
          std::max(seg.a.y, seg.b.y), x0, y0, x1, y1);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x)
        cells_[static_cast<size_t>(y) * static_cast<size_t>(nx_) + x].push_back(id);
  }

  // Calls f(item) once for every segment whose bucket lies within r of p.
  template <class F>
  void visit(glm::dvec2 p, double r, F&& f) {
    ++query_;
    int x0, y0, x1, y1;
    range(p.x - r, p.y - r, p.x + r, p.y + r, x0, y0, x1, y1);
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        for (uint32_t id : cells_[static_cast<size_t>(y) * static_cast<size_t>(nx_) + x]) {
          if (mark_[id] == query_) continue;
          mark_[id] = query_;
          f(items_[id]);
        }
      }
    }
  }

 private:
  void range(double ax, double ay, double bx, double by, int& x0, int& y0, int& x1, int& y1) const {
    auto cx = [&](double v) { return std::clamp(static_cast<int>(std::floor(v / cell_)), 0, nx_ - 1); };
    auto cy = [&](double v) { return std::clamp(static_cast<int>(std::floor(v / cell_)), 0, ny_ - 1); };
    x0 = cx(ax);
    x1 = cx(bx);
    y0 = cy(ay);
    y1 = cy(by);
  }

  double cell_;
  int nx_, ny_;
  std::vector<std::vector<uint32_t>> cells_;
  std::vector<Item> items_;
  std::vector<uint32_t> mark_;
  uint32_t query_ = 0;
};

// A line that stops just short of the contour or of another line leaves a gap
// that the triangulation bridges with a triangle spanning the depth step.
// Each end within `radius` of another constraint is extended onto it (the
// triangulation splits the segment it lands on).
void snapEnds(std::vector<Polyline>& lines, const std::vector<Polyline>& loops, double radius, int w, int h) {
  SegmentGrid grid(w, h, 16.0);
  for (const Polyline& l : loops)
    for (size_t k = 0; k < l.size(); ++k) grid.add({l[k], l[(k + 1) % l.size()]}, -1, static_cast<int>(k));
  std::vector<size_t> sizes;
  for (size_t li = 0; li < lines.size(); ++li) {
    sizes.push_back(lines[li].size());
    for (size_t k = 0; k + 1 < lines[li].size(); ++k)
      grid.add({lines[li][k], lines[li][k + 1]}, static_cast<int>(li), static_cast<int>(k));
  }
  for (size_t li = 0; li < lines.size(); ++li) {
    for (int end = 0; end < 2; ++end) {
      Polyline& own = lines[li];
      const glm::dvec2 e = end == 0 ? own.front() : own.back();
      double best = radius;
      glm::dvec2 target(0.0);
      bool found = false;
      grid.visit(e, radius, [&](const SegmentGrid::Item& it) {
        // Skip the line's own segment at this end.
        if (it.owner == static_cast<int>(li) &&
            ((end == 0 && it.k == 0) || (end == 1 && it.k + 2 == static_cast<int>(sizes[li]))))
          return;
        double t = 0.0;
        const double d = pointSegmentDistance(e, it.seg.a, it.seg.b, &t);
        if (d < best && d > 1e-9) {
          best = d;
          target = it.seg.a + (it.seg.b - it.seg.a) * t;
          found = true;
        }
      });
      if (!found) continue;
      if (end == 0)
        own.insert(own.begin(), target);
      else
        own.push_back(target);
    }
  }
}

// ---------------------------------------------------------------------------
// Step 5 (S97 §4.2 "reprojection"). A vertex on a discrepancy line or on the
// contour has two depths, one per side. Each (triangle, corner) therefore
// takes its depth from a covered pixel on the triangle's own side, which
// keeps triangles from stretching across the step (the "rubber sheet" of
// Decoret 99 §3).

// The covered pixel that speaks for corner v of triangle (v, o1, o2): aim at
// q, 1.5 px from the corner toward the centroid (deeper into the triangle
// than the corner, whose nearest pixels may lie across a line that the
// polygonal approximation moved by a fraction of a pixel), and take the
// covered pixel nearest to q (within 2 px) whose centre lies inside the
// triangle; for a triangle too thin to hold a pixel centre there, the pixel
// under q or the nearest covered one.
bool pickPixel(const Image& im, glm::dvec2 v, glm::dvec2 o1, glm::dvec2 o2, int& px, int& py) {
  auto cross = [](glm::dvec2 p, glm::dvec2 q) { return p.x * q.y - p.y * q.x; };
  const glm::dvec2 centroid = (v + o1 + o2) / 3.0;
  const double len = glm::length(centroid - v);
  const glm::dvec2 q = len > 0.0 ? v + (centroid - v) * (std::min(1.5, len) / len) : v;
  const int qx = static_cast<int>(std::floor(q.x)), qy = static_cast<int>(std::floor(q.y));
  const double area = cross(o1 - v, o2 - v);
  double best = std::numeric_limits<double>::infinity();
  bool found = false;
  if (area != 0.0) {
    for (int y = qy - 3; y <= qy + 3; ++y) {
      for (int x = qx - 3; x <= qx + 3; ++x) {
        if (!im.covered(x, y)) continue;
        const glm::dvec2 c(x + 0.5, y + 0.5);
        const double s0 = cross(o1 - v, c - v) / area;
        const double s1 = cross(o2 - o1, c - o1) / area;
        const double s2 = cross(v - o2, c - o2) / area;
        if (s0 < 0.0 || s1 < 0.0 || s2 < 0.0) continue;
        const double d = glm::dot(c - q, c - q);
        // Farther away, the extrapolation to the corner would cross more
        // surface than the pixel under q does.
        if (d < best && d <= 4.0) {
          best = d;
          px = x;
          py = y;
          found = true;
        }
      }
    }
  }
  if (found) return true;
  if (im.covered(qx, qy)) {
    px = qx;
    py = qy;
    return true;
  }
  for (int y = qy - 3; y <= qy + 3; ++y) {
    for (int x = qx - 3; x <= qx + 3; ++x) {
      if (!im.covered(x, y)) continue;
      const glm::dvec2 c(x + 0.5, y + 0.5);
      const double d = glm::dot(c - q, c - q);
      if (d < best) {
        best = d;
        px = x;
        py = y;
        found = true;
      }
    }
  }
  return found;
}

// Inverse depth at image point v, extrapolated from pixel (px, py) with the
// pixel's inverse-depth gradient: 1/z is affine in image space over a plane,
// so this is exact on planes, where a plain pixel lookup would be off by up
// to 1.5 px worth of slope. Neighbours across a step (relative difference
// above the threshold) are not used for the gradient.
double invDepthAt(const Image& im, int px, int py, glm::dvec2 v, const DepthMeshOptions& opt) {
  const double w = im.inv[im.at(px, py)];
  // Neighbour at offset k on the same surface: no discrepancy between them.
  auto same = [&](size_t k, double& wn) {
    const int x = px + kDx[k], y = py + kDy[k];
    if (!im.covered(x, y)) return false;
    wn = im.inv[im.at(x, y)];
    return pairDiscrepancy(im, px, py, k, opt.planar_prediction) <= opt.discrepancy_threshold;
  };
  // Change of 1/z from the pixel centre to the vertex along the axis of
  // offsets k (+) and k + 2 (-), for an offset of o pixels. The gradient is
  // one-sided, from the vertex's side first: at a crease that is the face the
  // vertex lies on.
  auto along = [&](size_t k, double o) {
    if (o == 0.0) return 0.0;
    const size_t kt = o > 0.0 ? k : k + 2, ka = o > 0.0 ? k + 2 : k;
    double wt = 0.0, wa = 0.0;
    const bool t = same(kt, wt), a = same(ka, wa);
    const double g = t ? wt - w : (a ? w - wa : 0.0);  // per pixel toward the vertex
    const double dist = std::abs(o);
    double dw = g * dist;
    // Is the vertex inside the surface's samples along this axis (the
    // pixels up to and including the one past the vertex continue the
    // surface)? If not, the surface ends somewhere before the vertex; on a
    // surface seen at a grazing angle (ground near its far edge: tens of
    // percent per pixel) the extrapolation would run far past the real
    // edge, so beyond the last sample it is capped at a quarter of the
    // threshold (1 % by default).
    // The image border is not an edge: the surface goes on.
    const int steps = static_cast<int>(std::ceil(dist));
    int x = px, y = py;
    for (int j = 1; j <= steps; ++j) {
      const int nx = x + kDx[kt], ny = y + kDy[kt];
      if (!im.in(nx, ny)) break;
      if (!im.covered(nx, ny) ||
          pairDiscrepancy(im, x, y, kt, opt.planar_prediction) > opt.discrepancy_threshold) {
        const double cap = std::abs(g) * (j - 1) + 0.25 * opt.discrepancy_threshold * w;
        dw = std::clamp(dw, -cap, cap);
        break;
      }
      x = nx;
      y = ny;
    }
    return dw;
  };
  const double ox = v.x - (px + 0.5), oy = v.y - (py + 0.5);
  const double wv = w + along(0, ox) + along(1, oy);
  // Past the horizon of a plane, or a runaway gradient: keep the pixel's own.
  if (!(wv > 0.2 * w && wv < 5.0 * w)) return w;
  return wv;
}

// Never trust sizes or the camera.
bool validInputs(const CaptureImage& img, const PinholeCamera& cam, const DepthMeshOptions& opt, std::string& why) {
  if (img.width <= 0 || img.height <= 0) {
    why = "image has no pixels (" + std::to_string(img.width) + "x" + std::to_string(img.height) + ")";
    return false;
  }
  if (img.width > 32768 || img.height > 32768) {
    why = "image larger than 32768 px on a side";
    return false;
  }
  const size_t n = static_cast<size_t>(img.width) * static_cast<size_t>(img.height);
  if (img.depth.size() != n) {
    why = "depth has " + std::to_string(img.depth.size()) + " values, expected " + std::to_string(n);
    return false;
  }
  if (!img.mask.empty() && img.mask.size() != n) {
    why = "mask has " + std::to_string(img.mask.size()) + " values, expected 0 or " + std::to_string(n);
    return false;
  }
  if (!img.rgba.empty() && img.rgba.size() != 4 * n) {
    why = "rgba has " + std::to_string(img.rgba.size()) + " bytes, expected 0 or " + std::to_string(4 * n);
    return false;
  }
  if (cam.width != img.width || cam.height != img.height) {
    why = "camera is " + std::to_string(cam.width) + "x" + std::to_string(cam.height) + ", image " +
          std::to_string(img.width) + "x" + std::to_string(img.height);
    return false;
  }
  auto finite3 = [](const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
  };
  if (!finite3(cam.eye) || !finite3(cam.forward) || !finite3(cam.right) || !finite3(cam.up) ||
      glm::length(cam.forward) == 0.0 || glm::length(cam.right) == 0.0 || glm::length(cam.up) == 0.0) {
    why = "camera has a non-finite or zero vector";
    return false;
  }
  if (!(cam.tan_half_x > 0.0) || !(cam.tan_half_y > 0.0) || !std::isfinite(cam.tan_half_x) ||
      !std::isfinite(cam.tan_half_y)) {
    why = "camera field of view must be finite and positive";
    return false;
  }
  if (!(opt.discrepancy_threshold > 0.0) || !(opt.contour_tolerance_px >= 0.0) ||
      !(opt.line_tolerance_px >= 0.0) || opt.grid_spacing_px <= 0) {
    why = "options: threshold and grid spacing must be positive, tolerances non-negative";
    return false;
  }

  return true;
}

// The depth as covered pixels and inverse depths; false when nothing is covered.
bool loadImage(const CaptureImage& img, Image& im, std::string& why) {
  const size_t n = static_cast<size_t>(img.width) * static_cast<size_t>(img.height);
  im.w = img.width;
  im.h = img.height;
  im.cov.assign(n, 0);
  im.inv.assign(n, 0.0);
  size_t coveredCount = 0;
  for (size_t p = 0; p < n; ++p) {
    const float z = img.depth[p];
    const bool geometry = img.mask.empty() || img.mask[p] != 0;
    // NaN fails the comparisons. Depths outside [1 um, 1e15 m] are treated as
    // background too: float positions could not tell their vertices apart.
    if (geometry && z >= 1e-6f && z <= 1e15f) {
      im.cov[p] = 1;
      im.inv[p] = 1.0 / static_cast<double>(z);
      ++coveredCount;
    }
  }
  if (coveredCount == 0) {
    why = "nothing covered: the mask (or the depth) is all background";
    return false;
  }

  return true;
}

// 1. External contour(s), simplified; 2. discrepancy lines. As constraint
// segments, the contours' first.
std::vector<Segment2> constraintsOf(const Image& im, const DepthMeshOptions& opt, DepthMeshStats& st,
                                    std::vector<Polyline>& loops) {
  loops = traceContours(im);
  for (Polyline& l : loops) l = simplifyClosed(l, opt.contour_tolerance_px);
  st.contours = loops.size();
  const Discrepancy dis = discrepancyImage(im, opt);
  std::vector<Polyline> lines = extractChains(im, dis, opt, st.discrepancy_chains);
  snapEnds(lines, loops, 2.5, im.w, im.h);
  std::vector<Segment2> constraints;
  for (const Polyline& l : loops)
    for (size_t k = 0; k < l.size(); ++k) constraints.push_back({l[k], l[(k + 1) % l.size()]});
  st.contour_segments = constraints.size();
  for (const Polyline& l : lines)
    for (size_t k = 0; k + 1 < l.size(); ++k) constraints.push_back({l[k], l[k + 1]});
  st.discrepancy_segments = constraints.size() - st.contour_segments;
  return constraints;
}

// The constraints, bucketed for the clearance tests of the grid and of
// refinement.
SegmentGrid constraintIndex(const Image& im, const std::vector<Segment2>& constraints) {
  SegmentGrid index(im.w, im.h, 16.0);
  for (size_t k = 0; k < constraints.size(); ++k) index.add(constraints[k], 0, static_cast<int>(k));
  return index;
}

// True when `p` is at least `r` from every constraint.
bool clearOf(SegmentGrid& lines, glm::dvec2 p, double r) {
  bool clear = true;
  lines.visit(p, r, [&](const SegmentGrid::Item& it) { clear = clear && pointSegmentDistance(p, it.seg.a, it.seg.b) >= r; });
  return clear;
}

// 3. Regular grid (S97: "to impose a minimal sampling density"), spaced `s`
// pixels: the points kept (`gridUsed`) and the segments that join them
// (`gridSegs`). Points on pixel centres, kept away from the constraints (a point next to a line
// only makes slivers). triangulateSegments takes segments, not points, so
// each row's neighbouring points are joined by a constraint segment where
// the whole span is covered (a grid of squares triangulates into the same
// right triangles either way); a point without a row neighbour is joined
// to the point below or above, and one with neither is dropped.
void gridOf(const Image& im, SegmentGrid& lines, const ContourParity& parity, int s, std::vector<Segment2>& gridSegs,
            std::vector<glm::dvec2>& gridUsed) {
  const int gw = im.w / s + 1, gh = im.h / s + 1;
  const double clearance = std::clamp(0.3 * s, 1.5, 8.0);
  std::vector<uint8_t> gridOk(static_cast<size_t>(gw) * static_cast<size_t>(gh), 0);
  auto gpos = [&](int i, int j) {
    return glm::dvec2(std::floor((i + 0.5) * s) + 0.5, std::floor((j + 0.5) * s) + 0.5);
  };
  for (int j = 0; j < gh; ++j) {
    for (int i = 0; i < gw; ++i) {
      const glm::dvec2 g = gpos(i, j);
      if (g.x >= im.w || g.y >= im.h) continue;
      if (!im.covered(static_cast<int>(g.x), static_cast<int>(g.y)) || !parity.inside(g)) continue;
      gridOk[static_cast<size_t>(j) * static_cast<size_t>(gw) + static_cast<size_t>(i)] =
          clearOf(lines, g, clearance) ? 1 : 0;
    }
  }
  auto ok = [&](int i, int j) {
    return i >= 0 && j >= 0 && i < gw && j < gh &&
           gridOk[static_cast<size_t>(j) * static_cast<size_t>(gw) + static_cast<size_t>(i)] != 0;
  };
  auto spanCovered = [&](glm::dvec2 a, glm::dvec2 b) {
    const int steps = static_cast<int>(std::ceil(glm::length(b - a)));
    for (int k = 0; k <= steps; ++k) {
      const glm::dvec2 p = a + (b - a) * (static_cast<double>(k) / std::max(1, steps));
      if (!im.covered(static_cast<int>(p.x), static_cast<int>(p.y))) return false;
    }
    return true;
  };
  for (int j = 0; j < gh; ++j) {
    for (int i = 0; i < gw; ++i) {
      if (!ok(i, j)) continue;
      const glm::dvec2 g = gpos(i, j);
      bool linked = false;
      if (ok(i + 1, j) && spanCovered(g, gpos(i + 1, j))) {
        gridSegs.push_back({g, gpos(i + 1, j)});
        linked = true;
      }
      if (ok(i - 1, j) && spanCovered(gpos(i - 1, j), g)) linked = true;
      for (int dj : {1, -1}) {
        if (linked) break;
        if (ok(i, j + dj) && spanCovered(g, gpos(i, j + dj))) {
          gridSegs.push_back({g, gpos(i, j + dj)});
          linked = true;
        }
      }
      if (linked) gridUsed.push_back(g);
    }
  }
}

// 4. Constrained Delaunay triangulation (S97 §4.2, their ref. 25) over the
// contour, the discrepancy lines and the grid, in (x, -y).
bool triangulate(const std::vector<Segment2>& constraints, const std::vector<Segment2>& gridSegs,
                 const std::vector<glm::dvec2>& points, const ContourParity& parity, Triangulation& tri,
                 std::string& why) {
  std::vector<Segment2> all;
  all.reserve(constraints.size() + gridSegs.size());
  for (const Segment2& c : constraints) all.push_back({{c.a.x, -c.a.y}, {c.b.x, -c.b.y}});
  for (const Segment2& c : gridSegs) all.push_back({{c.a.x, -c.a.y}, {c.b.x, -c.b.y}});
  std::vector<glm::dvec2> flipped(points.size());
  for (size_t k = 0; k < points.size(); ++k) flipped[k] = {points[k].x, -points[k].y};
  std::string terr;
  if (triangulateSegments(all, [&](glm::dvec2 c) { return parity.inside({c.x, -c.y}); }, tri, terr, &flipped))
    return true;
  why = "triangulation: " + terr;
  return false;
}

// One corner of a kept triangle: its triangulation vertex and depth.
struct Corner {
  uint32_t vid;
  double z;
  size_t slot;  // index into the kept triangles' corner list
};

// 5. Depth per (triangle, corner), at image positions `pos`; triangles
// degenerate in the image or without a depth at a corner are dropped.
std::vector<Corner> cornerDepths(const Image& im, const Triangulation& tri, const std::vector<glm::dvec2>& pos,
                                 const DepthMeshOptions& opt) {
  std::vector<Corner> corners;
  corners.reserve(tri.indices.size());
  for (size_t t = 0; t + 2 < tri.indices.size(); t += 3) {
    const uint32_t id[3] = {tri.indices[t], tri.indices[t + 1], tri.indices[t + 2]};
    const glm::dvec2 a = pos[id[0]], b = pos[id[1]], c = pos[id[2]];
    const double area2 = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    if (std::abs(area2) < 1e-9) continue;  // degenerate in the image
    std::array<double, 3> z{};
    bool good = true;
    for (int k = 0; k < 3 && good; ++k) {
      const glm::dvec2 v = pos[id[k]], o1 = pos[id[(k + 1) % 3]], o2 = pos[id[(k + 2) % 3]];
      int px = 0, py = 0;
      good = pickPixel(im, v, o1, o2, px, py);
      if (good) {
        z[static_cast<size_t>(k)] = 1.0 / invDepthAt(im, px, py, v, opt);
        good = std::isfinite(z[static_cast<size_t>(k)]) && z[static_cast<size_t>(k)] > 0.0;
      }
    }
    if (!good) continue;
    const size_t slot = corners.size();
    for (int k = 0; k < 3; ++k)
      corners.push_back({id[k], z[static_cast<size_t>(k)], slot + static_cast<size_t>(k)});
  }
  return corners;
}

// 5b. Refinement. S97 §4.2 constrains the triangulation by the contour and
// the depth steps; a crease (the ground in front of a wall meeting the wall)
// is no step, and a triangle of the grid that spans it joins a ground point
// to points up the wall. From the vantage point it shows the right texels;
// from anywhere else it is a sheet through the air in front of the wall,
// seen as a needle rising from the street across the facade. So in each
// triangle, the covered pixel whose depth the triangle's plane misses most
// (1/z is affine in the image over a plane), if by more than the
// discrepancy threshold, is returned as a vertex for the next
// triangulation. Only pixels inside a surface count: all 8 neighbours
// covered, and 3 px or more from the constraints and the triangle's
// corners (a vertex next to a line only makes slivers, and a vertex's depth
// is taken from a pixel inside its triangles).
std::vector<glm::dvec2> misfits(const Image& im, const std::vector<glm::dvec2>& pos,
                                const std::vector<Corner>& corners, SegmentGrid& lines, const DepthMeshOptions& opt) {
  constexpr double kClear = 3.0;
  std::vector<glm::dvec2> out;
  for (size_t c = 0; c + 2 < corners.size(); c += 3) {
    const glm::dvec2 a = pos[corners[c].vid], b = pos[corners[c + 1].vid], d = pos[corners[c + 2].vid];
    const double wa = 1.0 / corners[c].z, wb = 1.0 / corners[c + 1].z, wd = 1.0 / corners[c + 2].z;
    const double det = (b.x - a.x) * (d.y - a.y) - (b.y - a.y) * (d.x - a.x);
    if (std::abs(det) < 1.0) continue;  // under half a pixel of area
    const int x0 = std::max(0, int(std::floor(std::min({a.x, b.x, d.x})))),
              x1 = std::min(im.w - 1, int(std::ceil(std::max({a.x, b.x, d.x})))),
              y0 = std::max(0, int(std::floor(std::min({a.y, b.y, d.y})))),
              y1 = std::min(im.h - 1, int(std::ceil(std::max({a.y, b.y, d.y}))));
    double worst = opt.discrepancy_threshold;
    glm::dvec2 at(-1.0);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        if (!im.covered(x, y) || im.onContour(x, y)) continue;
        const glm::dvec2 p(x + 0.5, y + 0.5);
        const double lb = ((p.x - a.x) * (d.y - a.y) - (p.y - a.y) * (d.x - a.x)) / det;
        const double ld = ((b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x)) / det;
        const double la = 1.0 - lb - ld;
        if (la < 0.0 || lb < 0.0 || ld < 0.0) continue;
        if (glm::length(p - a) < kClear || glm::length(p - b) < kClear || glm::length(p - d) < kClear) continue;
        const double e = relInv(la * wa + lb * wb + ld * wd, im.inv[im.at(x, y)]);
        if (e > worst && clearOf(lines, p, kClear)) worst = e, at = p;
      }
    if (at.x >= 0.0) out.push_back(at);
  }
  std::sort(out.begin(), out.end(), [](glm::dvec2 u, glm::dvec2 v) { return u.y != v.y ? u.y < v.y : u.x < v.x; });
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

// An output vertex: a triangulation vertex at one of its depths.
struct OutVertex {
  uint32_t vid;
  double z;
};

// Each position's depths clustered: within half the threshold they are one
// surface (merged, so continuous surfaces stay watertight), beyond it they are
// the two sides of a step (split). `slotToVertex`: each corner's vertex.
std::vector<OutVertex> clusterCorners(const std::vector<Corner>& corners, double thr,
                                      std::vector<uint32_t>& slotToVertex, size_t& splitExtra) {
  std::vector<size_t> order(corners.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    if (corners[a].vid != corners[b].vid) return corners[a].vid < corners[b].vid;
    if (corners[a].z != corners[b].z) return corners[a].z < corners[b].z;
    return corners[a].slot < corners[b].slot;
  });
  slotToVertex.assign(corners.size(), 0);
  std::vector<OutVertex> verts;
  const double mergeTol = 0.5 * thr;
  splitExtra = 0;
  for (size_t a = 0; a < order.size();) {
    size_t b = a;
    double sum = 0.0;
    const Corner& first = corners[order[a]];
    while (b < order.size() && corners[order[b]].vid == first.vid &&
           corners[order[b]].z <= first.z * (1.0 + mergeTol)) {
      sum += corners[order[b]].z;
      ++b;
    }
    if (a > 0 && corners[order[a - 1]].vid == first.vid) ++splitExtra;
    const uint32_t vi = static_cast<uint32_t>(verts.size());
    verts.push_back({first.vid, sum / static_cast<double>(b - a)});
    for (size_t k = a; k < b; ++k) slotToVertex[corners[order[k]].slot] = vi;
    a = b;
  }
  return verts;
}

// The mesh: each vertex unprojected at its depth, triangles that survive in
// 3D, wound counter-clockwise as the camera sees them.
void emitMesh(const Image& im, const PinholeCamera& cam, const std::vector<glm::dvec2>& pos,
              const std::vector<OutVertex>& verts, const std::vector<uint32_t>& slotToVertex, geo::MeshData& out,
              DepthMeshDebug* dbg) {
  // Counter-clockwise on screen is counter-clockwise seen from the camera
  // when right x up points back at the eye (a right-handed camera, the usual
  // case); flip for a left-handed basis.
  const bool flip = glm::dot(glm::cross(cam.right, cam.up), cam.forward) > 0.0;
  std::vector<glm::vec3> world(verts.size());
  for (size_t k = 0; k < verts.size(); ++k) {
    const glm::dvec2 p = pos[verts[k].vid];
    world[k] = glm::vec3(cam.eye + cam.ray(p.x, p.y) * verts[k].z);
  }
  auto finiteF = [](const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
  };
  // Only vertices of surviving triangles are written.
  std::vector<uint32_t> remap(verts.size(), UINT32_MAX);
  auto emit = [&](uint32_t v) {
    if (remap[v] == UINT32_MAX) {
      remap[v] = static_cast<uint32_t>(out.positions.size() / 3);
      const glm::dvec2 p = pos[verts[v].vid];
      out.positions.insert(out.positions.end(), {world[v].x, world[v].y, world[v].z});
      out.texcoords.push_back(static_cast<float>(p.x / im.w));
      out.texcoords.push_back(static_cast<float>(p.y / im.h));
      if (dbg) dbg->image_pos.push_back(p);
    }
    out.indices.push_back(remap[v]);
  };
  for (size_t c = 0; c + 2 < slotToVertex.size(); c += 3) {
    const uint32_t a = slotToVertex[c], b = slotToVertex[c + 1], d = slotToVertex[c + 2];
    if (a == b || b == d || a == d) continue;
    // Absurd depths or fields of view can overflow float: drop, never emit inf.
    if (!finiteF(world[a]) || !finiteF(world[b]) || !finiteF(world[d])) continue;
    // Drop triangles that collapse in 3D.
    const glm::dvec3 pa(world[a]), pb(world[b]), pd(world[d]);
    if (glm::length(glm::cross(pb - pa, pd - pa)) == 0.0) continue;
    emit(a);
    emit(flip ? d : b);
    emit(flip ? b : d);
  }
}

bool buildImpl(const CaptureImage& img, const PinholeCamera& cam, const DepthMeshOptions& opt,
               geo::MeshData& out, DepthMeshStats& st, std::string& why, DepthMeshDebug* dbg) {
  Image im;
  if (!validInputs(img, cam, opt, why) || !loadImage(img, im, why)) return false;
  std::vector<Polyline> loops;
  const std::vector<Segment2> constraints = constraintsOf(im, opt, st, loops);
  const ContourParity parity(loops, im.h);
  // 3. Regular grid (S97: "to impose a minimal sampling density").
  std::vector<Segment2> gridSegs;
  std::vector<glm::dvec2> gridUsed;
  SegmentGrid lines = constraintIndex(im, constraints);
  gridOf(im, lines, parity, opt.grid_spacing_px, gridSegs, gridUsed);
  st.grid_points = gridUsed.size();
  // 4. and 5. Triangulation and a depth per (triangle, corner), made again
  // with the pixels where a triangle missed the surface as vertices (5b).
  Triangulation tri;
  std::vector<glm::dvec2> pos, extra;
  std::vector<Corner> corners;
  for (int round = 0;; ++round) {
    if (!triangulate(constraints, gridSegs, extra, parity, tri, why)) return false;
    pos.resize(tri.vertices.size());
    for (size_t k = 0; k < pos.size(); ++k) pos[k] = {tri.vertices[k].x, -tri.vertices[k].y};
    corners = cornerDepths(im, tri, pos, opt);
    if (round >= opt.refine_rounds) break;
    const std::vector<glm::dvec2> more = misfits(im, pos, corners, lines, opt);
    if (more.empty()) break;
    extra.insert(extra.end(), more.begin(), more.end());
  }
  st.refine_points = extra.size();
  // Then one output vertex per (position, depth cluster).
  std::vector<uint32_t> slotToVertex;
  const std::vector<OutVertex> verts = clusterCorners(corners, opt.discrepancy_threshold, slotToVertex, st.split_vertices);
  emitMesh(im, cam, pos, verts, slotToVertex, out, dbg);
  if (out.indices.empty()) {
    why = "no triangle survived re-projection";
    return false;
  }
  st.triangles = out.indices.size() / 3;
  st.vertices = out.positions.size() / 3;
  if (dbg) {
    for (size_t k = 0; k < constraints.size(); ++k)
      (k < st.contour_segments ? dbg->contour : dbg->discrepancy).push_back(constraints[k]);
    dbg->grid = gridUsed;
  }
  return true;
}

}  // namespace

bool buildDepthMesh(const CaptureImage& img, const PinholeCamera& cam, const DepthMeshOptions& opt,
                    geo::MeshData& out, DepthMeshStats* stats, std::string& why, DepthMeshDebug* debug) {
  const auto t0 = std::chrono::steady_clock::now();
  out.clear();
  why.clear();
  if (debug) *debug = DepthMeshDebug{};
  DepthMeshStats st;
  bool ok = false;
  try {
    ok = buildImpl(img, cam, opt, out, st, why, debug);
  } catch (const std::exception& e) {  // std::bad_alloc on absurd sizes
    why = std::string("depth mesh failed: ") + e.what();
  } catch (...) {
    why = "depth mesh failed: unknown exception";
  }
  if (!ok) {
    out.clear();
    if (debug) *debug = DepthMeshDebug{};
  }
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (stats) *stats = st;
  return ok;
}

size_t hangSkirt(CaptureImage& img, int rows) {
  const int w = img.width, h = img.height;
  const size_t n = size_t(w) * size_t(h);
  if (w <= 0 || h <= 0 || img.depth.size() != n || img.mask.size() != n || img.rgba.size() != 4 * n) return 0;
  auto at = [w](int x, int y) { return size_t(y) * size_t(w) + size_t(x); };
  size_t count = 0;
  for (int x = 0; x < w; ++x) {
    for (int y = h - 2; y >= 0; --y) {  // bottom up: a skirt never hangs from a skirt
      const size_t p = at(x, y);
      if (!img.mask[p]) continue;
      for (int k = 1; k <= rows && y + k < h; ++k) {
        const size_t q = at(x, y + k);
        if (img.mask[q] || img.rgba[4 * q + 3] != 0) break;
        img.depth[q] = img.depth[p];
        img.mask[q] = 1;
        std::copy_n(&img.rgba[4 * p], 4, &img.rgba[4 * q]);
        ++count;
      }
    }
  }
  return count;
}

size_t dropEdgeOnTriangles(geo::MeshData& mesh, const glm::dvec3& eye, const glm::dvec3& viewer, double max_cos) {
  if (!(max_cos > 0.0)) return 0;
  auto at = [&](uint32_t i) {
    return glm::dvec3(mesh.positions[3 * size_t(i)], mesh.positions[3 * size_t(i) + 1], mesh.positions[3 * size_t(i) + 2]);
  };
  size_t kept = 0;
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    const glm::dvec3 a = at(mesh.indices[t]), b = at(mesh.indices[t + 1]), c = at(mesh.indices[t + 2]);
    const glm::dvec3 n = glm::cross(b - a, c - a), mid = (a + b + c) / 3.0;
    const double len = glm::length(n);
    bool drop = false;
    if (len > 0.0 && glm::length(mid - eye) > 0.0 && glm::length(mid - viewer) > 0.0) {
      const glm::dvec3 u = n / len;
      const double from_eye = std::abs(glm::dot(u, glm::normalize(mid - eye)));
      const double from_viewer = std::abs(glm::dot(u, glm::normalize(mid - viewer)));
      drop = std::abs(u.y) < 0.9 && from_eye < max_cos && from_viewer > 2.0 * from_eye;
    }
    if (drop) continue;
    for (size_t k = 0; k < 3; ++k) mesh.indices[kept * 3 + k] = mesh.indices[t + k];
    ++kept;
  }
  const size_t dropped = mesh.indices.size() / 3 - kept;
  mesh.indices.resize(kept * 3);
  return dropped;
}

}  // namespace blvd::bake
