// GRPH and CELL section encodings (docs/package-format.md). Little-endian,
// fixed-size records, counts first; parse checks every count against the bytes
// left and every index against its table before anything uses it.
#include <cmath>

#include "core/bytes.h"
#include "graph/street_graph.h"

namespace blvd::graph {
namespace {
constexpr uint32_t kGraphVersion = 1;

void putCsr(core::ByteWriter& w, const Csr& c) {
  w.put<uint32_t>(static_cast<uint32_t>(c.items.size()));
  for (uint32_t o : c.offsets) w.put(o);
  for (uint32_t x : c.items) w.put(x);
}

void getCsr(core::ByteReader& r, Csr& c, size_t lists, const char* name) {
  const uint32_t n = r.getCount(4);
  if ((lists + 1) * 4 > r.remaining()) r.fail(std::string(name) + ": offsets truncated");
  c.offsets.resize(lists + 1);
  for (auto& o : c.offsets) o = r.get<uint32_t>();
  if (n * 4ull > r.remaining()) r.fail(std::string(name) + ": items truncated");
  c.items.resize(n);
  for (auto& x : c.items) x = r.get<uint32_t>();
  if (c.offsets[0] != 0 || c.offsets.back() != n) r.fail(std::string(name) + ": offsets do not span the items");
  for (size_t i = 0; i < lists; ++i)
    if (c.offsets[i] > c.offsets[i + 1]) r.fail(std::string(name) + ": offsets decrease");
}
}  // namespace

std::vector<uint8_t> serializeGraph(const StreetGraph& g) {
  core::ByteWriter w;
  w.put(kGraphVersion);
  w.put<uint32_t>(static_cast<uint32_t>(g.vertices.size()));
  for (const Vertex& v : g.vertices) {
    w.put(v.p.x);
    w.put(v.p.y);
    w.put(v.halfedge);
    w.put<uint32_t>(static_cast<uint32_t>(v.kind));
  }
  w.put<uint32_t>(static_cast<uint32_t>(g.halfedges.size()));
  for (const HalfEdge& h : g.halfedges) {
    w.put(h.origin);
    w.put(h.twin);
    w.put(h.next);
    w.put(h.face);
    w.put(h.pts_begin);
    w.put(h.pts_count);
    w.put(h.length);
    w.put(h.width);
    w.put<uint8_t>(static_cast<uint8_t>(h.road_class));
    w.put(h.flags);
    w.put(h.layer);
    w.put<uint8_t>(0);
    w.put(h.osm_way);
  }
  w.put<uint32_t>(static_cast<uint32_t>(g.faces.size()));
  for (const Face& f : g.faces) {
    w.put(f.halfedge);
    w.put<uint32_t>(f.unbounded ? 1 : 0);
    w.put(f.area);
  }
  w.put<uint32_t>(static_cast<uint32_t>(g.points.size()));
  for (const glm::dvec2& p : g.points) {
    w.put(p.x);
    w.put(p.y);
  }
  return std::move(w.bytes());
}

std::vector<uint8_t> serializeCells(const StreetGraph& g) {
  core::ByteWriter w;
  w.put(kGraphVersion);
  w.put<uint32_t>(static_cast<uint32_t>(g.halfedges.size()));
  putCsr(w, g.successors);
  putCsr(w, g.predecessors);
  putCsr(w, g.local_blocks);
  return std::move(w.bytes());
}

void parseGraph(const uint8_t* data, size_t size, uint64_t file_offset, StreetGraph& g) {
  core::ByteReader r(data, size, "graph section GRPH", file_offset);
  if (r.get<uint32_t>() != kGraphVersion) r.fail("unknown graph version");
  g = StreetGraph{};
  g.vertices.resize(r.getCount(24));
  for (Vertex& v : g.vertices) {
    v.p.x = r.get<double>();
    v.p.y = r.get<double>();
    v.halfedge = r.get<uint32_t>();
    const uint32_t k = r.get<uint32_t>();
    if (k > 3) r.fail("bad vertex kind");
    v.kind = static_cast<VertexKind>(k);
  }
  g.halfedges.resize(r.getCount(44));
  for (HalfEdge& h : g.halfedges) {
    h.origin = r.get<uint32_t>();
    h.twin = r.get<uint32_t>();
    h.next = r.get<uint32_t>();
    h.face = r.get<uint32_t>();
    h.pts_begin = r.get<uint32_t>();
    h.pts_count = r.get<uint32_t>();
    h.length = r.get<float>();
    h.width = r.get<float>();
    const uint8_t rc = r.get<uint8_t>();
    if (rc > static_cast<uint8_t>(RoadClass::Other)) r.fail("bad road class");
    h.road_class = static_cast<RoadClass>(rc);
    h.flags = r.get<uint8_t>();
    h.layer = r.get<int8_t>();
    r.get<uint8_t>();
    h.osm_way = r.get<int64_t>();
  }
  g.faces.resize(r.getCount(16));
  for (Face& f : g.faces) {
    f.halfedge = r.get<uint32_t>();
    f.unbounded = r.get<uint32_t>() != 0;
    f.area = r.get<double>();
  }
  g.points.resize(r.getCount(16));
  for (glm::dvec2& p : g.points) {
    p.x = r.get<double>();
    p.y = r.get<double>();
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) r.fail("non-finite point");
    // A package's local frame spans a city or a region: a point 10,000 km out
    // is garbage (and would size a segment grid past any memory).
    if (std::abs(p.x) > kMaxPointM || std::abs(p.y) > kMaxPointM) r.fail("point more than 10,000 km from the origin");
  }
  // Index checks up front so nothing downstream can go out of range.
  const size_t V = g.vertices.size(), H = g.halfedges.size(), F = g.faces.size(), P = g.points.size();
  for (const Vertex& v : g.vertices)
    if (v.halfedge != kNone && v.halfedge >= H) r.fail("vertex half-edge out of range");
  for (const HalfEdge& h : g.halfedges)
    if (h.origin >= V || h.twin >= H || h.next >= H || h.face >= F || h.pts_count < 2 ||
        h.pts_begin > P || h.pts_count > P - h.pts_begin)
      r.fail("half-edge index out of range");
  for (const Face& f : g.faces)
    if (f.halfedge != kNone && f.halfedge >= H) r.fail("face half-edge out of range");
}

void parseCells(const uint8_t* data, size_t size, uint64_t file_offset, StreetGraph& g) {
  core::ByteReader r(data, size, "cell section CELL", file_offset);
  if (r.get<uint32_t>() != kGraphVersion) r.fail("unknown cell version");
  const uint32_t n = r.get<uint32_t>();
  if (n != g.halfedges.size()) r.fail("cell count does not match the graph's half-edges");
  getCsr(r, g.successors, n, "successors");
  getCsr(r, g.predecessors, n, "predecessors");
  getCsr(r, g.local_blocks, n, "local blocks");
  for (uint32_t x : g.successors.items)
    if (x >= n) r.fail("successor out of range");
  for (uint32_t x : g.predecessors.items)
    if (x >= n) r.fail("predecessor out of range");
  for (uint32_t x : g.local_blocks.items)
    if (x >= g.faces.size()) r.fail("local block out of range");
}

}  // namespace blvd::graph
