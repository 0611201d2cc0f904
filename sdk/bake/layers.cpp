#include "bake/layers.h"
#include "core/math.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

namespace blvd::bake {
namespace {

using core::kPi;

double cross(glm::dvec2 o, glm::dvec2 a, glm::dvec2 b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); }

// Separating-axis test between two convex polygons (CCW point lists; a
// segment or point is a degenerate convex polygon).
bool convexIntersect(const std::vector<glm::dvec2>& a, const std::vector<glm::dvec2>& b) {
  auto separated = [](const std::vector<glm::dvec2>& p, const std::vector<glm::dvec2>& q) {
    const size_t n = p.size();
    for (size_t i = 0; i < n; ++i) {
      const glm::dvec2 e = p[(i + 1) % n] - p[i];
      const glm::dvec2 axis(-e.y, e.x);
      if (axis.x == 0 && axis.y == 0) continue;
      double pmin = 1e300, pmax = -1e300, qmin = 1e300, qmax = -1e300;
      for (const auto& v : p) pmin = std::min(pmin, glm::dot(v, axis)), pmax = std::max(pmax, glm::dot(v, axis));
      for (const auto& v : q) qmin = std::min(qmin, glm::dot(v, axis)), qmax = std::max(qmax, glm::dot(v, axis));
      if (pmax < qmin || qmax < pmin) return true;
    }
    return false;
  };
  if (a.empty() || b.empty()) return false;
  return !separated(a, b) && !separated(b, a);
}

std::vector<glm::dvec2> sample(const std::vector<glm::dvec2>& hull, size_t max_points) {
  if (hull.size() <= max_points) return hull;
  std::vector<glm::dvec2> out;
  for (size_t i = 0; i < max_points; ++i) out.push_back(hull[i * hull.size() / max_points]);
  return out;
}

}  // namespace

double angleVariation(glm::dvec2 P, glm::dvec2 Q, glm::dvec2 A, glm::dvec2 B) {
  const double len = glm::length(Q - P);
  if (len < 1e-9) return 0.0;  // a point cell: the angle does not vary
  const glm::dvec2 u = (Q - P) / len;
  glm::dvec2 n(-u.y, u.x);
  double yA = glm::dot(A - P, n);
  if (std::abs(yA) < 1e-9) return kPi;
  if (yA < 0) n = -n, yA = -yA;
  // The paper's frame (Figure 3): PQ on the x axis, A at (0, 1).
  const double xA0 = glm::dot(A - P, u);
  auto toFrame = [&](glm::dvec2 p) { return glm::dvec2((glm::dot(p - P, u) - xA0) / yA, glm::dot(p - P, n) / yA); };
  const glm::dvec2 b = toFrame(B);
  const double xP = toFrame(P).x, xQ = toFrame(Q).x;
  const double lo = std::min(xP, xQ), hi = std::max(xP, xQ);
  auto angle = [&](double x) {
    const glm::dvec2 ma(-x, 1.0), mb(b.x - x, b.y);
    const double la = glm::length(ma), lb = glm::length(mb);
    if (la < 1e-15 || lb < 1e-15) return 0.0;
    return std::acos(std::clamp(glm::dot(ma, mb) / (la * lb), -1.0, 1.0));
  };
  double candidates[5] = {xP, xQ, 0, 0, 0};
  int nc = 2;
  if (std::abs(b.y - 1.0) < 1e-12) {
    candidates[nc++] = b.x * 0.5;  // H: where the median of [AB] meets (PQ)
  } else {
    candidates[nc++] = b.x / (1.0 - b.y);                        // (3)
    const double disc = b.y * ((b.y - 1.0) * (b.y - 1.0) + b.x * b.x);
    if (disc >= 0) {
      candidates[nc++] = (b.x + std::sqrt(disc)) / (1.0 - b.y);  // (4)
      candidates[nc++] = (b.x - std::sqrt(disc)) / (1.0 - b.y);  // (5)
    }
  }
  double amin = std::numeric_limits<double>::max(), amax = -1;
  for (int i = 0; i < nc; ++i) {
    const double x = candidates[i];
    if (!(x >= lo - 1e-12 && x <= hi + 1e-12)) continue;
    const double a = angle(x);
    amin = std::min(amin, a);
    amax = std::max(amax, a);
  }
  return amax - amin;
}

std::vector<glm::dvec2> convexHull(std::vector<glm::dvec2> pts) {
  std::sort(pts.begin(), pts.end(), [](glm::dvec2 a, glm::dvec2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  if (pts.size() < 3) return pts;
  std::vector<glm::dvec2> h(2 * pts.size());
  size_t k = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], pts[i]) <= 0) --k;
    h[k++] = pts[i];
  }
  for (size_t i = pts.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(h[k - 2], h[k - 1], pts[i]) <= 0) --k;
    h[k++] = pts[i];
  }
  h.resize(k - 1);
  return h;
}

double objectWeight(glm::dvec2 P, glm::dvec2 Q, const LayerObject& a, const LayerObject& b, size_t max_points) {
  // Critical zones (D99 §4.1, Figure 2): hull of the object and the cell.
  auto zone = [&](const LayerObject& o) {
    std::vector<glm::dvec2> pts = o.hull;
    pts.push_back(P);
    pts.push_back(Q);
    return convexHull(pts);
  };
  if (!convexIntersect(a.hull, zone(b)) && !convexIntersect(b.hull, zone(a))) return 0.0;
  const auto sa = sample(a.hull, max_points), sb = sample(b.hull, max_points);
  double w = 0;
  for (const auto& pa : sa)
    for (const auto& pb : sb) w = std::max(w, angleVariation(P, Q, pa, pb));
  return w * std::max(a.weight_scale, b.weight_scale);
}

LayerAssignment assignLayers(glm::dvec2 P, glm::dvec2 Q, const std::vector<LayerObject>& objects,
                             double threshold_rad) {
  LayerAssignment out;
  const size_t n = objects.size();
  out.weights.assign(n * n, 0.0);
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j)
      out.weights[i * n + j] = out.weights[j * n + i] = objectWeight(P, Q, objects[i], objects[j]);

  // Nearest first: the objects that move most against the background seed layers.
  auto distance = [&](const LayerObject& o) {
    double d = 1e300;
    const glm::dvec2 m = 0.5 * (P + Q);
    for (const auto& p : o.hull) d = std::min(d, glm::length(p - m));
    return d;
  };
  std::vector<size_t> order(n);
  for (size_t i = 0; i < n; ++i) order[i] = i;
  std::vector<double> dist(n);
  for (size_t i = 0; i < n; ++i) dist[i] = distance(objects[i]);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return dist[a] < dist[b]; });

  struct Box {
    glm::dvec2 lo{1e300}, hi{-1e300};
    void add(const std::vector<glm::dvec2>& pts) {
      for (const auto& p : pts) lo = glm::min(lo, p), hi = glm::max(hi, p);
    }
    double area() const { return hi.x < lo.x ? 0 : (hi.x - lo.x) * (hi.y - lo.y); }
  };
  std::vector<Box> boxes;
  for (size_t i : order) {
    size_t best = SIZE_MAX;
    double best_area = 1e300;
    for (size_t l = 0; l < out.layers.size(); ++l) {
      bool ok = true;
      for (uint32_t j : out.layers[l])
        if (out.weights[i * n + j] > threshold_rad) {
          ok = false;
          break;
        }
      if (!ok) continue;
      Box b = boxes[l];
      b.add(objects[i].hull);
      if (b.area() < best_area) best_area = b.area(), best = l;
    }
    if (best == SIZE_MAX) {
      out.layers.emplace_back();
      boxes.emplace_back();
      best = out.layers.size() - 1;
    }
    out.layers[best].push_back(static_cast<uint32_t>(i));
    boxes[best].add(objects[i].hull);
  }
  return out;
}

double capLayers(LayerAssignment& la, size_t n, size_t max_layers) {
  double worst = 0;
  if (max_layers == 0) max_layers = 1;
  while (la.layers.size() > max_layers) {
    std::vector<uint32_t> last = std::move(la.layers.back());
    la.layers.pop_back();
    for (uint32_t i : last) {
      size_t best = 0;
      double best_w = 1e300;
      for (size_t l = 0; l < la.layers.size(); ++l) {
        double w = 0;
        for (uint32_t j : la.layers[l]) w = std::max(w, la.weights[i * n + j]);
        if (w < best_w) best_w = w, best = l;
      }
      worst = std::max(worst, best_w);
      la.layers[best].push_back(i);
    }
  }
  return worst;
}

double pixelsToRadians(double pixels, double width_px, double fov_x_deg) {
  return pixels * (fov_x_deg * kPi / 180.0) / width_px;
}

}  // namespace blvd::bake
