#include "stream/paged_graph.h"

#include <cmath>
#include <cstring>
#include <vector>

namespace blvd::stream {
namespace {

// Record sizes of the GRPH, CELL and SIDX tables (docs/package-format.md).
constexpr uint32_t kVertexBytes = 24, kHalfEdgeBytes = 44, kFaceBytes = 16, kPointBytes = 16;
constexpr uint32_t kGraphVersion = 1;
const char* const kListNames[3] = {"successors", "predecessors", "local blocks"};

uint32_t readU32(const uint8_t* p) {
  uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}

// Walks a section's counted tables without reading them: each count is
// read from the file (never touched through the mapping).
struct Cursor {
  const package::PackageReader& reader;
  const package::Span& s;
  const char* section;
  const PageSource* source;
  size_t at = 0;
  std::string error;

  bool count(uint32_t* n, uint64_t record, const char* what) {
    if (at + 4 > s.size) return fail(std::string(what) + ": count truncated");
    if (source) source->ensure(s.offset + at, 4);
    uint8_t word[4];
    std::string err;
    if (reader.read(s.offset + at, 4, word, err) != core::Status::Ok) throw core::Error(core::Status::Io, err);
    *n = readU32(word);
    at += 4;
    if (record * *n > s.size - at) return fail(std::string(what) + ": " + std::to_string(*n) + " records overrun the section");
    return true;
  }
  const uint8_t* skip(uint64_t bytes) {
    const uint8_t* p = s.data + at;
    at += bytes;
    return p;
  }
  bool fail(const std::string& why) {
    if (error.empty()) error = std::string(section) + " at file offset " + std::to_string(s.offset + at) + ": " + why;
    return false;
  }
};

}  // namespace

core::Status PagedGraph::locate(const package::PackageReader& reader, const PageSource* source, std::string& err) {
  package::Span g, c;
  for (auto [tag, span] : {std::pair{package::kSectionGraph, &g}, std::pair{package::kSectionCells, &c}}) {
    const core::Status st = tableSection(reader, source, tag, *span, err);
    if (st == core::Status::NotFound) {
      err = reader.name() + ": missing section " + package::tagToString(tag);
      return core::Status::Corrupt;
    }
    if (st != core::Status::Ok) return st;
  }
  grph_ = g;
  cell_ = c;
  Cursor gc{reader, g, "graph section GRPH", source, 0, {}};
  uint32_t version = 0;
  bool ok = gc.count(&version, 0, "version") && (version == kGraphVersion || gc.fail("unknown graph version")) &&
            gc.count(&vertices_, kVertexBytes, "vertices") && gc.skip(uint64_t(vertices_) * kVertexBytes) &&
            gc.count(&halfedges_, kHalfEdgeBytes, "half-edges") &&
            (at_halfedges_ = gc.skip(uint64_t(halfedges_) * kHalfEdgeBytes)) && gc.count(&faces_, kFaceBytes, "faces") &&
            gc.skip(uint64_t(faces_) * kFaceBytes) && gc.count(&points_, kPointBytes, "points") &&
            (at_points_ = gc.skip(uint64_t(points_) * kPointBytes));
  Cursor cc{reader, c, "cell section CELL", source, 0, {}};
  uint32_t cells = 0;
  ok = ok && cc.count(&version, 0, "version") && (version == kGraphVersion || cc.fail("unknown cell version")) &&
       cc.count(&cells, 0, "cells") && (cells == halfedges_ || cc.fail("cell count does not match the graph's half-edges"));
  for (int l = 0; ok && l < 3; ++l) {
    ok = cc.count(&lists_[l].count, 0, kListNames[l]) && (uint64_t(cells) + 1) * 4 <= c.size - cc.at;
    if (!ok) {
      cc.fail(std::string(kListNames[l]) + ": offsets truncated");
      break;
    }
    at_lists_[l][0] = cc.skip((uint64_t(cells) + 1) * 4);
    ok = uint64_t(lists_[l].count) * 4 <= c.size - cc.at || cc.fail(std::string(kListNames[l]) + ": items truncated");
    if (ok) at_lists_[l][1] = cc.skip(uint64_t(lists_[l].count) * 4);
  }
  if (!ok) {
    err = reader.name() + ": " + (gc.error.empty() ? cc.error : gc.error);
    return core::Status::Corrupt;
  }
  return core::Status::Ok;
}

core::Status PagedGraph::openGrid(const package::PackageReader& reader, const PageSource* source,
                                  package::Span& sidx, std::string& err) {
  const core::Status st = tableSection(reader, source, package::kSectionSpatialIndex, sidx, err);
  if (st != core::Status::Ok) return st;
  if (source) source->ensure(sidx.offset, std::min<uint64_t>(sidx.size, graph::kGridHeaderBytes));
  std::vector<uint8_t> head;
  if (const core::Status rs = reader.copy(sidx, head, err, graph::kGridHeaderBytes); rs != core::Status::Ok) return rs;
  stored_ = graph::parseGridShape(head.data(), sidx.size, sidx.offset);  // reads the header only
  return core::Status::Ok;
}

core::Status PagedGraph::open(const package::PackageReader& reader, std::string& err, const PagedGraphDesc& desc,
                              const PageSource* source) {
  *this = PagedGraph{};
  name_ = reader.name();
  package::Span sidx;
  const bool has_grid = reader.hasSection(package::kSectionSpatialIndex);
  try {
    core::Status st = locate(reader, source, err);
    if (st == core::Status::Ok && has_grid) st = openGrid(reader, source, sidx, err);
    if (st != core::Status::Ok) return st;
    cache_ = std::make_unique<PageCache>(reader, desc.pages ? desc.pages : PagedGraphDesc::kDefaultPages,
                                         desc.page_bytes ? desc.page_bytes : PagedGraphDesc::kDefaultPageBytes, source);
    t_halfedges_ = cache_->addTable(at_halfedges_, halfedges_, kHalfEdgeBytes);
    t_points_ = cache_->addTable(at_points_, points_, kPointBytes);
    for (int l = 0; l < 3; ++l) {
      lists_[l].offsets = cache_->addTable(at_lists_[l][0], halfedges_ + 1, 4);
      lists_[l].items = cache_->addTable(at_lists_[l][1], lists_[l].count, 4);
    }
    if (has_grid) {
      t_grid_offsets_ = cache_->addTable(sidx.data + stored_.offsets_at, uint32_t(stored_.shape.cellCount() + 1), 4);
      t_grid_entries_ = cache_->addTable(sidx.data + stored_.entries_at, stored_.entries, 8);
    }
    if (source) return core::Status::Ok;  // each read checks its record
    check();
    if (has_grid) checkGrid();
  } catch (const core::Error& e) {
    err = e.what();
    return e.status();
  }
  if (!has_grid) {
    grid_ = std::make_unique<graph::SegmentGrid>();
    grid_->build(*this);
  }
  return core::Status::Ok;
}

uint64_t PagedGraph::fileOffset(const uint8_t* p) const {
  const package::Span& s = p >= grph_.data && p < grph_.data + grph_.size ? grph_ : cell_;
  return s.offset + static_cast<uint64_t>(p - s.data);
}

void PagedGraph::bad(const uint8_t* table, uint64_t record, uint64_t i, const std::string& why) const {
  throw core::Error(core::Status::Corrupt, name_ + ": " + why + " (record " + std::to_string(i) + " at file offset " +
                                               std::to_string(fileOffset(table) + record * i) + ")");
}

// One pass over every record the runtime reads: halfedge(), point() and
// item() check theirs (parseGraph's and parseCells's checks), this adds that
// each list's offsets span its items; the cache bounds what the pass holds.
void PagedGraph::check() const {
  for (uint32_t h = 0; h < halfedges_; ++h) halfedge(h);
  for (uint32_t i = 0; i < points_; ++i) point(i);
  for (int l = 0; l < 3; ++l) {
    uint32_t prev = 0;
    for (uint32_t h = 0; h <= halfedges_; ++h) {
      const uint32_t o = u32(lists_[l].offsets, h);
      if ((h == 0 && o != 0) || o < prev || (h == halfedges_ && o != lists_[l].count))
        bad(at_lists_[l][0], 4, h, std::string("cell section CELL: ") + kListNames[l] + ": offsets do not span the items");
      prev = o;
    }
    for (uint32_t i = 0; i < lists_[l].count; ++i) item(static_cast<graph::CellList>(l), i);
  }
}

void PagedGraph::checkGrid() const {
  if (stored_.shape.nx == 0 && stored_.entries == 0) return;
  const uint32_t cells = static_cast<uint32_t>(stored_.shape.cellCount());
  uint32_t prev = 0;
  for (uint32_t c = 0; c <= cells; ++c) {
    const uint32_t o = u32(t_grid_offsets_, c);
    if ((c == 0 && o != 0) || o < prev || (c == cells && o != stored_.entries))
      throw core::Error(core::Status::Corrupt, name_ + ": spatial index SIDX: offsets do not span the entries at grid cell " +
                                                   std::to_string(c));
    prev = o;
  }
  for (uint32_t i = 0; i < stored_.entries; ++i) gridEntry(i);
}

graph::SegmentGrid::Entry PagedGraph::gridEntry(uint32_t i) const {
  graph::SegmentGrid::Entry e;
  cache_->read(t_grid_entries_, i, &e);
  if (e.halfedge >= halfedges_ || e.point + 1 >= points_)
    throw core::Error(core::Status::Corrupt, name_ + ": spatial index SIDX: entry " + std::to_string(i) + " out of range");
  return e;
}

uint32_t PagedGraph::u32(uint32_t table, uint32_t i) const {
  uint32_t v;
  cache_->read(table, i, &v);
  return v;
}

graph::HalfEdge PagedGraph::halfedge(uint32_t h) const {
  uint8_t b[kHalfEdgeBytes];
  cache_->read(t_halfedges_, h, b);
  graph::HalfEdge e;
  std::memcpy(&e.origin, b + 0, 4);
  std::memcpy(&e.twin, b + 4, 4);
  std::memcpy(&e.next, b + 8, 4);
  std::memcpy(&e.face, b + 12, 4);
  std::memcpy(&e.pts_begin, b + 16, 4);
  std::memcpy(&e.pts_count, b + 20, 4);
  std::memcpy(&e.length, b + 24, 4);
  std::memcpy(&e.width, b + 28, 4);
  e.road_class = static_cast<graph::RoadClass>(b[32]);
  e.flags = b[33];
  e.layer = static_cast<int8_t>(b[34]);
  std::memcpy(&e.osm_way, b + 36, 8);
  if (e.origin >= vertices_ || e.twin >= halfedges_ || e.next >= halfedges_ || e.face >= faces_ || e.pts_count < 2 ||
      e.pts_begin > points_ || e.pts_count > points_ - e.pts_begin)
    bad(at_halfedges_, kHalfEdgeBytes, h, "graph section GRPH: half-edge index out of range");
  if (static_cast<uint8_t>(e.road_class) > static_cast<uint8_t>(graph::RoadClass::Other))
    bad(at_halfedges_, kHalfEdgeBytes, h, "graph section GRPH: bad road class");
  return e;
}

glm::dvec2 PagedGraph::point(uint32_t i) const {
  double p[2];
  cache_->read(t_points_, i, p);
  if (!std::isfinite(p[0]) || !std::isfinite(p[1])) bad(at_points_, kPointBytes, i, "graph section GRPH: non-finite point");
  if (std::abs(p[0]) > graph::kMaxPointM || std::abs(p[1]) > graph::kMaxPointM)
    bad(at_points_, kPointBytes, i, "graph section GRPH: point more than 10,000 km from the origin");
  return {p[0], p[1]};
}

void PagedGraph::listBounds(graph::CellList list, uint32_t h, uint32_t* first, uint32_t* last) const {
  const Lists& l = lists(list);
  *first = u32(l.offsets, h);
  *last = u32(l.offsets, h + 1);
  if (*first > *last || *last > l.count)
    bad(at_lists_[static_cast<int>(list)][0], 4, h,
        std::string("cell section CELL: ") + kListNames[static_cast<int>(list)] + ": offsets do not span the items");
}

uint32_t PagedGraph::item(graph::CellList list, uint32_t i) const {
  const uint32_t v = u32(lists(list).items, i);
  if (v >= (list == graph::CellList::LocalBlocks ? faces_ : halfedges_))
    bad(at_lists_[static_cast<int>(list)][1], 4, i,
        std::string("cell section CELL: ") + kListNames[static_cast<int>(list)] + ": item out of range");
  return v;
}

uint32_t PagedGraph::gridEntryCount() const {
  return grid_ ? static_cast<uint32_t>(grid_->entryCount()) : stored_.entries;
}

void PagedGraph::segmentsNear(double x, double y, double r, EntryFn fn, void* ctx) const {
  if (grid_) {
    grid_->query(x, y, r, [&](const graph::SegmentGrid::Entry& e) { fn(e, ctx); });
    return;
  }
  int x0, x1, y0, y1;
  if (!stored_.shape.cellsNear(x, y, r, &x0, &x1, &y0, &y1)) return;
  for (int gy = y0; gy <= y1; ++gy)
    for (int gx = x0; gx <= x1; ++gx) {
      const uint32_t c = static_cast<uint32_t>(gy) * stored_.shape.nx + gx;
      const uint32_t last = u32(t_grid_offsets_, c + 1);
      for (uint32_t i = u32(t_grid_offsets_, c); i < last; ++i) fn(gridEntry(i), ctx);
    }
}

uint64_t PagedGraph::bytes() const {
  return sizeof(*this) + (cache_ ? cache_->bytes() : 0) + (grid_ ? grid_->bytes() : 0);
}

}  // namespace blvd::stream
