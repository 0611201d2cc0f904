#include "bake/street_map.h"

#include <algorithm>
#include <cstring>
#include <unordered_map>
#include <unordered_set>

#include <glm/geometric.hpp>

#include <CGAL/Arr_consolidated_curve_data_traits_2.h>
#include <CGAL/Arr_landmarks_point_location.h>
#include <CGAL/Arr_segment_traits_2.h>
#include <CGAL/Arrangement_2.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>

#include "core/log.h"
#include "core/status.h"

namespace blvd::bake {
namespace {
using K = CGAL::Exact_predicates_exact_constructions_kernel;
using SegTraits = CGAL::Arr_segment_traits_2<K>;
using Traits = CGAL::Arr_consolidated_curve_data_traits_2<SegTraits, uint32_t>;  // data: street index
using Arr = CGAL::Arrangement_2<Traits>;
using Locator = CGAL::Arr_landmarks_point_location<Arr>;

struct PointKey {
  uint64_t x, y;
  bool operator==(const PointKey& o) const { return x == o.x && y == o.y; }
};
struct PointKeyHash {
  size_t operator()(const PointKey& k) const { return std::hash<uint64_t>()(k.x * 0x9E3779B97F4A7C15ull ^ k.y); }
};
PointKey keyOf(double x, double y) {
  PointKey k;
  std::memcpy(&k.x, &x, 8);
  std::memcpy(&k.y, &y, 8);
  return k;
}
glm::dvec2 toVec(const Arr::Point_2& p) { return {CGAL::to_double(p.x()), CGAL::to_double(p.y())}; }

template <typename T>
void addUnique(std::vector<T>& v, T x) {
  if (std::find(v.begin(), v.end(), x) == v.end()) v.push_back(x);
}
}  // namespace

struct StreetMap::Impl {
  Arr arr;
  std::unique_ptr<Locator> locator;
  std::unordered_map<const void*, uint32_t> face_index;
};

namespace {

using NodeStreets = std::unordered_map<PointKey, std::vector<uint32_t>, PointKeyHash>;

// Builds the half-edge graph from the arrangement of the streets' segments
// (Sillion 97 §4.1), one step a method, in the order the constructor calls
// them.
class GraphBuilder {
 public:
  GraphBuilder(const std::vector<OsmStreet>& streets, Arr& arr, std::unordered_map<const void*, uint32_t>& face_index,
               graph::StreetGraph& g)
      : streets_(streets), arr_(arr), face_index_(face_index), g_(g) {}

  // Which streets have an OSM node at a given location (streets meet, a
  // junction, only where both have a node), and the arrangement of all segments.
  void insertStreets() {
    std::vector<Traits::Curve_2> curves;
    for (uint32_t s = 0; s < streets_.size(); ++s) {
      const auto& pts = streets_[s].pts;
      for (size_t i = 0; i < pts.size(); ++i) {
        addUnique(node_streets_[keyOf(pts[i].x, pts[i].y)], s);
        if (i + 1 < pts.size() && pts[i] != pts[i + 1])
          curves.emplace_back(SegTraits::Curve_2(K::Point_2(pts[i].x, pts[i].y), K::Point_2(pts[i + 1].x, pts[i + 1].y)),
                              s);
      }
    }
    CGAL::insert(arr_, curves.begin(), curves.end());
  }

  // Graph vertices are the arrangement vertices of degree != 2; faces are the arrangement's.
  void addVerticesAndFaces() {
    for (auto v = arr_.vertices_begin(); v != arr_.vertices_end(); ++v)
      if (v->degree() != 2) addVertex(v);
    for (auto f = arr_.faces_begin(); f != arr_.faces_end(); ++f) {
      graph::Face gf;
      gf.unbounded = f->is_unbounded();
      face_index_.emplace(&*f, static_cast<uint32_t>(g_.faces.size()));
      g_.faces.push_back(gf);
    }
  }

  // Every chain of arrangement half-edges between graph vertices becomes a
  // pair of twin half-edges.
  void walkChains() {
    for (auto v = arr_.vertices_begin(); v != arr_.vertices_end(); ++v) {
      if (v->degree() == 2 || v->degree() == 0) continue;
      auto c = v->incident_halfedges(), c0 = c;  // half-edges whose target is v
      do {
        Arr::Halfedge_const_handle out = c->twin();
        if (!chain_of_.count(&*out)) walk(out);
      } while (++c != c0);
    }
    // Closed loops made only of degree-2 vertices (an isolated ring road):
    // promote one vertex to a graph vertex so the loop becomes one edge.
    for (auto he = arr_.halfedges_begin(); he != arr_.halfedges_end(); ++he) {
      if (chain_of_.count(&*he)) continue;
      addVertex(he->source());
      walk(he);
    }
  }

  // next, each vertex's half-edge, and each face's boundary and signed area.
  void linkFaces() {
    for (uint32_t h = 0; h < g_.halfedges.size(); ++h) g_.halfedges[h].next = first_of_.at(&*last_of_[h]->next());
    for (uint32_t h = 0; h < g_.halfedges.size(); ++h) {
      graph::Vertex& v = g_.vertices[g_.halfedges[h].origin];
      if (v.halfedge == graph::kNone) v.halfedge = h;
    }
    for (auto f = arr_.faces_begin(); f != arr_.faces_end(); ++f) {
      if (f->is_unbounded()) continue;
      graph::Face& gf = g_.faces[face_index_.at(&*f)];
      gf.halfedge = chain_of_.at(&*f->outer_ccb());
      double area2 = 0;
      auto c = f->outer_ccb(), c0 = c;
      do {
        const glm::dvec2 a = toVec(c->source()->point()), b = toVec(c->target()->point());
        area2 += a.x * b.y - b.x * a.y;
      } while (++c != c0);
      gf.area = 0.5 * area2;
    }
  }

  // Connectivity at each half-edge's end vertex: which outgoing half-edges a
  // vehicle may take. Streets connect where both have an OSM node, or where a
  // street simply continues through a grade-separated crossing.
  std::vector<std::vector<uint32_t>> connections() const {
    std::vector<std::vector<uint32_t>> out_of(g_.vertices.size());
    for (uint32_t h = 0; h < g_.halfedges.size(); ++h) out_of[g_.halfedges[h].origin].push_back(h);
    std::vector<std::vector<uint32_t>> connects(g_.halfedges.size());
    for (uint32_t h = 0; h < g_.halfedges.size(); ++h) {
      const uint32_t v = g_.endVertex(h);
      const glm::dvec2 p = g_.vertices[v].p;
      const auto ns = node_streets_.find(keyOf(p.x, p.y));
      auto hasNode = [&](uint32_t s) {
        return ns != node_streets_.end() && std::find(ns->second.begin(), ns->second.end(), s) != ns->second.end();
      };
      for (uint32_t o : out_of[v]) {
        if (o == g_.halfedges[h].twin && out_of[v].size() > 1) continue;  // no U-turns except at dead ends
        bool ok = false;
        for (uint32_t a : streets_at_end_[h])
          for (uint32_t b : streets_at_start_[o])
            if (a == b || (hasNode(a) && hasNode(b))) ok = true;
        if (ok) connects[h].push_back(o);
      }
    }
    return connects;
  }

 private:
  // A dead end, bend, junction or grade-separated crossing: streets cross
  // without meeting unless each has an OSM node there.
  graph::VertexKind kindOf(Arr::Vertex_const_handle v, const glm::dvec2& p) const {
    if (v->degree() == 1) return graph::VertexKind::DeadEnd;
    if (v->degree() == 2) return graph::VertexKind::Bend;
    const auto ns = node_streets_.find(keyOf(p.x, p.y));
    const size_t at_node = ns == node_streets_.end() ? 0 : ns->second.size();
    if (at_node >= 2) return graph::VertexKind::Junction;
    if (at_node == 0) return graph::VertexKind::Crossing;
    // One street has a node here: a junction only if every incident edge is that street (a way meeting itself).
    auto c = v->incident_halfedges(), c0 = c;
    do {
      const auto& d = c->curve().data();
      if (std::find(d.begin(), d.end(), ns->second[0]) == d.end()) return graph::VertexKind::Crossing;
    } while (++c != c0);
    return graph::VertexKind::Junction;
  }

  uint32_t addVertex(Arr::Vertex_const_handle v) {
    auto it = vertex_index_.find(&*v);
    if (it != vertex_index_.end()) return it->second;
    graph::Vertex gv;
    gv.p = toVec(v->point());
    gv.kind = kindOf(v, gv.p);
    g_.vertices.push_back(gv);
    const auto idx = static_cast<uint32_t>(g_.vertices.size() - 1);
    vertex_index_.emplace(&*v, idx);
    return idx;
  }

  // The twin pair of one chain: the street's attributes, the polyline both ways,
  // the length. Returns the forward half-edge; its twin follows it.
  uint32_t addEdgePair(const std::vector<Arr::Halfedge_const_handle>& chain) {
    const uint32_t h = static_cast<uint32_t>(g_.halfedges.size()), t = h + 1;
    graph::HalfEdge fwd, bwd;
    fwd.origin = vertex_index_.at(&*chain.front()->source());
    bwd.origin = vertex_index_.at(&*chain.back()->target());
    fwd.twin = t;
    bwd.twin = h;
    fwd.face = face_index_.at(&*chain.front()->face());
    bwd.face = face_index_.at(&*chain.front()->twin()->face());
    const OsmStreet& st = streets_[*chain.front()->curve().data().begin()];
    for (graph::HalfEdge* e : {&fwd, &bwd}) {
      e->road_class = st.road_class;
      e->width = st.width;
      e->layer = st.layer;
      e->osm_way = st.way_id;
      e->flags = static_cast<uint8_t>((st.oneway ? graph::kOneway : 0) | (st.bridge ? graph::kBridge : 0) |
                                      (st.tunnel ? graph::kTunnel : 0));
    }
    fwd.pts_begin = static_cast<uint32_t>(g_.points.size());
    g_.points.push_back(toVec(chain.front()->source()->point()));
    for (const auto& he : chain) g_.points.push_back(toVec(he->target()->point()));
    fwd.pts_count = static_cast<uint32_t>(chain.size() + 1);
    bwd.pts_begin = static_cast<uint32_t>(g_.points.size());
    for (size_t i = fwd.pts_count; i-- > 0;) g_.points.push_back(g_.points[fwd.pts_begin + i]);
    bwd.pts_count = fwd.pts_count;
    double len = 0;
    for (uint32_t i = 1; i < fwd.pts_count; ++i)
      len += glm::length(g_.points[fwd.pts_begin + i] - g_.points[fwd.pts_begin + i - 1]);
    fwd.length = bwd.length = static_cast<float>(len);
    g_.halfedges.push_back(fwd);
    g_.halfedges.push_back(bwd);
    return h;
  }

  // Follows arrangement half-edges from he0 to the next graph vertex, adds the
  // twin pair, and records which arrangement half-edges it covers (`first_of_`:
  // a chain's first one, `chain_of_`: every one) and the streets at each end.
  void walk(Arr::Halfedge_const_handle he0) {
    std::vector<Arr::Halfedge_const_handle> chain{he0};
    while (vertex_index_.find(&*chain.back()->target()) == vertex_index_.end()) {
      chain.push_back(chain.back()->next());
      if (chain.size() > arr_.number_of_halfedges()) throw core::Error(core::Status::Internal, "street chain does not end");
    }
    const uint32_t h = addEdgePair(chain), t = h + 1;
    first_of_[&*chain.front()] = h;
    first_of_[&*chain.back()->twin()] = t;
    for (const auto& he : chain) {
      chain_of_[&*he] = h;
      chain_of_[&*he->twin()] = t;
    }
    last_of_.push_back(chain.back());
    last_of_.push_back(chain.front()->twin());
    auto dataOf = [](Arr::Halfedge_const_handle he) {
      return std::vector<uint32_t>(he->curve().data().begin(), he->curve().data().end());
    };
    streets_at_start_.push_back(dataOf(chain.front()));
    streets_at_end_.push_back(dataOf(chain.back()));
    streets_at_start_.push_back(dataOf(chain.back()));
    streets_at_end_.push_back(dataOf(chain.front()));
  }

  const std::vector<OsmStreet>& streets_;
  Arr& arr_;
  std::unordered_map<const void*, uint32_t>& face_index_;
  graph::StreetGraph& g_;
  NodeStreets node_streets_;
  std::unordered_map<const void*, uint32_t> vertex_index_, first_of_, chain_of_;
  std::vector<Arr::Halfedge_const_handle> last_of_;  // per our half-edge
  std::vector<std::vector<uint32_t>> streets_at_start_, streets_at_end_;
};

}  // namespace

StreetMap::StreetMap(const std::vector<OsmStreet>& streets) : impl_(new Impl) {
  GraphBuilder b(streets, impl_->arr, impl_->face_index, graph_);
  b.insertStreets();
  b.addVerticesAndFaces();
  b.walkChains();
  b.linkFaces();
  computeCellLists(graph_, b.connections());
  impl_->locator.reset(new Locator(impl_->arr));
  BLVD_LOG_INFO("street map: %zu arrangement vertices, %zu graph vertices (%zu junctions), %zu edges, %zu faces",
                impl_->arr.number_of_vertices(), graph_.vertices.size(), graph_.junctionCount(),
                graph_.halfedges.size() / 2, graph_.faces.size());
}

StreetMap::~StreetMap() = default;

uint32_t StreetMap::locateFace(const glm::dvec2& p) const {
  const auto obj = impl_->locator->locate(K::Point_2(p.x, p.y));
  Arr::Face_const_handle f;
  if (const auto* fh = boost::get<Arr::Face_const_handle>(&obj)) {
    f = *fh;
  } else if (const auto* eh = boost::get<Arr::Halfedge_const_handle>(&obj)) {
    f = (*eh)->face();
  } else if (const auto* vh = boost::get<Arr::Vertex_const_handle>(&obj)) {
    f = (*vh)->is_isolated() ? (*vh)->face() : (*vh)->incident_halfedges()->face();
  } else {
    throw core::Error(core::Status::Internal, "point location returned nothing");
  }
  return impl_->face_index.at(&*f);
}

void computeCellLists(graph::StreetGraph& g, const std::vector<std::vector<uint32_t>>& connects_at_end) {
  const size_t H = g.halfedges.size();
  std::vector<std::vector<uint32_t>> pred(H);
  g.successors = {};
  g.predecessors = {};
  g.local_blocks = {};
  for (uint32_t h = 0; h < H; ++h) {
    g.successors.push(connects_at_end[h]);
    for (uint32_t s : connects_at_end[h]) pred[s].push_back(h);
  }
  for (uint32_t h = 0; h < H; ++h) g.predecessors.push(pred[h]);
  // Local model (Sillion 97 §4.1): the blocks on both sides of the street plus
  // the blocks that share its end junctions.
  std::vector<std::vector<uint32_t>> faces_at(g.vertices.size());
  for (uint32_t h = 0; h < H; ++h) addUnique(faces_at[g.halfedges[h].origin], g.halfedges[h].face);
  for (uint32_t h = 0; h < H; ++h) {
    std::vector<uint32_t> blocks;
    addUnique(blocks, g.halfedges[h].face);
    addUnique(blocks, g.halfedges[g.halfedges[h].twin].face);
    for (uint32_t v : {g.halfedges[h].origin, g.endVertex(h)})
      for (uint32_t f : faces_at[v]) addUnique(blocks, f);
    g.local_blocks.push(blocks);
  }
}

}  // namespace blvd::bake
