// Constrained Delaunay triangulation of dirty OSM polygons (see triangulate.h).
//
// This is the only translation unit that includes CGAL's triangulation
// headers: each one costs about 16 s and 730 MB to compile, so everything in
// bake that needs a triangulation goes through the two functions here.
//
// In/out marking follows the flood of CGAL's "polygon_triangulation" example
// (Triangulation_2 user manual, "Triangulating a Polygonal Domain"): walk the
// faces from the infinite face and flip in/out when crossing a constrained
// edge. The example counts every constrained edge as one crossing, which
// turns a hole that shares an edge with the outer ring into a filled area.
// Here each triangulation edge instead carries how many times the input
// rings walk it (Constrained_triangulation_plus_2 keeps every ring as the
// chain of triangulation vertices it passes through, including points where
// it was split by another ring), and only odd counts flip. That is the
// even-odd rule, and it is well defined: each ring is a closed walk in the
// triangulation's edge graph, the mod-2 sum of closed walks has even degree
// at every vertex, and the faces of such a graph are 2-colourable.
#include "bake/triangulate.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Constrained_triangulation_plus_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <exception>
#include <functional>
#include <map>
#include <unordered_map>
#include <utility>

namespace blvd::bake {
namespace {

struct FaceInfo {
  int parity = -1;  // -1 not reached yet, 0 outside, 1 inside (kept)
};

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_2<K>;
using Fbi = CGAL::Triangulation_face_base_with_info_2<FaceInfo, K>;
using Fb = CGAL::Constrained_triangulation_face_base_2<K, Fbi>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
// Exact_predicates_tag: constraints may intersect; intersection points are
// constructed in double precision, which is all an input in metres needs.
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<K, Tds, CGAL::Exact_predicates_tag>;
using Cdtp = CGAL::Constrained_triangulation_plus_2<Cdt>;
using Point = K::Point_2;
using VertexHandle = Cdtp::Vertex_handle;
using FaceHandle = Cdtp::Face_handle;

using EdgeKey = std::pair<const void*, const void*>;

EdgeKey edgeKey(VertexHandle a, VertexHandle b) {
  const void* pa = &*a;
  const void* pb = &*b;
  return std::less<const void*>()(pa, pb) ? EdgeKey(pa, pb) : EdgeKey(pb, pa);
}

bool finite(const glm::dvec2& p) { return std::isfinite(p.x) && std::isfinite(p.y); }

bool finite(const Ring& r) {
  return std::all_of(r.pts.begin(), r.pts.end(), [](const glm::dvec2& p) { return finite(p); });
}

// Ring points without consecutive repeats, the OSM closing point included.
std::vector<Point> cleanRing(const Ring& r) {
  std::vector<Point> pts;
  pts.reserve(r.pts.size());
  for (const glm::dvec2& p : r.pts) {
    Point q(p.x, p.y);
    if (pts.empty() || pts.back() != q) pts.push_back(q);
  }
  while (pts.size() > 1 && pts.front() == pts.back()) pts.pop_back();
  return pts;
}

size_t distinctCount(std::vector<Point> pts) {
  std::sort(pts.begin(), pts.end());
  return static_cast<size_t>(std::unique(pts.begin(), pts.end()) - pts.begin());
}

// True when not all points lie on one line (exact predicate, so a ring of
// nearly-collinear points with a tiny but real area still counts).
bool spansArea(const std::vector<Point>& pts) {
  size_t j = 1;
  while (j < pts.size() && pts[j] == pts[0]) ++j;
  for (size_t k = j + 1; k < pts.size(); ++k) {
    if (CGAL::orientation(pts[0], pts[j], pts[k]) != CGAL::COLLINEAR) return true;
  }
  return false;
}

// Gathers the kept faces (parity 1) into `out`, numbering only the vertices
// they use.
bool collect(const Cdtp& cdt, Triangulation& out, std::string& why) {
  std::unordered_map<const void*, uint32_t> index;
  auto idx = [&](VertexHandle v) {
    auto [it, added] = index.emplace(&*v, static_cast<uint32_t>(out.vertices.size()));
    if (added) out.vertices.emplace_back(v->point().x(), v->point().y());
    return it->second;
  };
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
    if (f->info().parity != 1) continue;
    // CGAL stores faces counter-clockwise, which is the order we promise.
    for (int i = 0; i < 3; ++i) out.indices.push_back(idx(f->vertex(i)));
    for (int i = 0; i < 3; ++i) {
      FaceHandle n = f->neighbor(i);
      if (cdt.is_infinite(n) || n->info().parity != 1) {
        // Edge i is opposite vertex i; walking ccw(i) -> cw(i) keeps this
        // counter-clockwise face on the left.
        out.boundary.push_back(idx(f->vertex(Cdtp::ccw(i))));
        out.boundary.push_back(idx(f->vertex(Cdtp::cw(i))));
      }
    }
  }
  if (out.indices.empty()) {
    why = "triangulation is empty (the rings enclose no area)";
    return false;
  }
  return true;
}

bool triangulateImpl(const Polygon2& poly, Triangulation& out, std::string& why) {
  if (!finite(poly.outer)) {
    why = "outer ring has a non-finite coordinate";
    return false;
  }
  for (size_t i = 0; i < poly.inners.size(); ++i) {
    if (!finite(poly.inners[i])) {
      why = "inner ring " + std::to_string(i) + " has a non-finite coordinate";
      return false;
    }
  }
  std::vector<Point> outer = cleanRing(poly.outer);
  if (distinctCount(outer) < 3) {
    why = "outer ring has fewer than 3 distinct points";
    return false;
  }
  if (!spansArea(outer)) {
    why = "outer ring has zero area (all points collinear)";
    return false;
  }

  Cdtp cdt;
  std::vector<Cdtp::Constraint_id> rings;
  rings.push_back(cdt.insert_constraint(outer.begin(), outer.end(), true));
  for (const Ring& inner : poly.inners) {
    std::vector<Point> pts = cleanRing(inner);
    // A hole without area would be walked back and forth and so flip
    // nothing; skipping it only saves vertices.
    if (distinctCount(pts) < 3 || !spansArea(pts)) continue;
    rings.push_back(cdt.insert_constraint(pts.begin(), pts.end(), true));
  }
  if (cdt.dimension() != 2) {
    why = "polygon has zero area";
    return false;
  }

  // How many times the rings walk each triangulation edge.
  std::map<EdgeKey, int> walks;
  for (Cdtp::Constraint_id cid : rings) {
    auto v = cdt.vertices_in_constraint_begin(cid);
    const auto end = cdt.vertices_in_constraint_end(cid);
    if (v == end) continue;
    VertexHandle prev = *v;
    for (++v; v != end; ++v) {
      if (!cdt.is_edge(prev, *v)) {
        why = "internal: a ring step is not a triangulation edge";
        return false;
      }
      ++walks[edgeKey(prev, *v)];
      prev = *v;
    }
  }

  // Breadth-first flood from the infinite face (outside, parity 0).
  std::deque<FaceHandle> queue;
  cdt.infinite_face()->info().parity = 0;
  queue.push_back(cdt.infinite_face());
  while (!queue.empty()) {
    FaceHandle f = queue.front();
    queue.pop_front();
    for (int i = 0; i < 3; ++i) {
      FaceHandle n = f->neighbor(i);
      if (n->info().parity != -1) continue;
      int flip = 0;
      if (f->is_constrained(i)) {
        auto it = walks.find(edgeKey(f->vertex(Cdtp::ccw(i)), f->vertex(Cdtp::cw(i))));
        if (it != walks.end()) flip = it->second & 1;
      }
      n->info().parity = f->info().parity ^ flip;
      queue.push_back(n);
    }
  }
  return collect(cdt, out, why);
}

bool triangulateSegmentsImpl(const std::vector<Segment2>& segments,
                             const std::function<bool(glm::dvec2)>& inside, Triangulation& out,
                             std::string& why, const std::vector<glm::dvec2>* points) {
  if (!inside) {
    why = "no inside predicate";
    return false;
  }
  Cdtp cdt;
  for (size_t i = 0; i < segments.size(); ++i) {
    const Segment2& s = segments[i];
    if (!finite(s.a) || !finite(s.b)) {
      why = "segment " + std::to_string(i) + " has a non-finite coordinate";
      return false;
    }
    if (s.a == s.b) continue;
    cdt.insert_constraint(Point(s.a.x, s.a.y), Point(s.b.x, s.b.y));
  }
  for (size_t i = 0; points && i < points->size(); ++i) {
    if (!finite((*points)[i])) {
      why = "point " + std::to_string(i) + " has a non-finite coordinate";
      return false;
    }
    cdt.insert(Point((*points)[i].x, (*points)[i].y));
  }
  if (cdt.dimension() != 2) {
    why = "segments span no area";
    return false;
  }
  for (auto f = cdt.all_faces_begin(); f != cdt.all_faces_end(); ++f) {
    f->info().parity = 0;
    if (cdt.is_infinite(f)) continue;
    glm::dvec2 c(0.0);
    for (int i = 0; i < 3; ++i) c += glm::dvec2(f->vertex(i)->point().x(), f->vertex(i)->point().y());
    if (inside(c / 3.0)) f->info().parity = 1;
  }
  return collect(cdt, out, why);
}

}  // namespace

bool triangulate(const Polygon2& poly, Triangulation& out, std::string& why) {
  out.clear();
  why.clear();
  bool ok = false;
  try {
    ok = triangulateImpl(poly, out, why);
  } catch (const std::exception& e) {
    // CGAL reports failed preconditions as exceptions (CGAL::Failure_exception).
    why = std::string("triangulation failed: ") + e.what();
  } catch (...) {
    why = "triangulation failed: unknown exception";
  }
  if (!ok) out.clear();
  return ok;
}

bool triangulateSegments(const std::vector<Segment2>& segments,
                         const std::function<bool(glm::dvec2)>& inside, Triangulation& out,
                         std::string& why, const std::vector<glm::dvec2>* points) {
  out.clear();
  why.clear();
  bool ok = false;
  try {
    ok = triangulateSegmentsImpl(segments, inside, out, why, points);
  } catch (const std::exception& e) {
    why = std::string("triangulation failed: ") + e.what();
  } catch (...) {
    why = "triangulation failed: unknown exception";
  }
  if (!ok) out.clear();
  return ok;
}

double signedArea(const Ring& ring) {
  const size_t n = ring.pts.size();
  if (n < 3) return 0.0;
  // Relative to the first point: local coordinates can be kilometres from the
  // origin while the ring is metres wide.
  const glm::dvec2 o = ring.pts[0];
  double twice = 0.0;
  for (size_t i = 1; i + 1 < n; ++i) {
    const glm::dvec2 a = ring.pts[i] - o;
    const glm::dvec2 b = ring.pts[i + 1] - o;
    twice += a.x * b.y - a.y * b.x;
  }
  return 0.5 * twice;
}

double area(const Triangulation& t) {
  double twice = 0.0;
  for (size_t i = 0; i + 2 < t.indices.size(); i += 3) {
    const glm::dvec2 a = t.vertices[t.indices[i]];
    const glm::dvec2 b = t.vertices[t.indices[i + 1]] - a;
    const glm::dvec2 c = t.vertices[t.indices[i + 2]] - a;
    twice += b.x * c.y - b.y * c.x;
  }
  return 0.5 * twice;
}

}  // namespace blvd::bake
