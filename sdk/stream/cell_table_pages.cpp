#include "stream/cell_table_pages.h"

#include <algorithm>
#include <cstring>
#include <tuple>
#include <vector>

#include "core/bytes.h"
#include "graph/cell_tables.h"

namespace blvd::stream {
namespace {

constexpr uint32_t kLayerBytes = 24;  // blob, triangles, vertices, width, height, run, block count

template <class T>
T at(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

// PVSA's and IMPO's headers, each reader left at its first cell's records.
void parseHeaders(core::ByteReader& rv, core::ByteReader& ri, uint32_t cells) {
  graph::CellTables display;
  graph::parseVisibilityHeader(rv, cells);
  graph::parseImpostorsHeader(ri, cells, display);
}

}  // namespace

core::Status CellTablePages::open(const package::PackageReader& reader, const graph::GraphSource& streets,
                                  uint32_t blocks, uint32_t pages, uint32_t page_bytes, std::string& err,
                                  const PageSource* source, uint32_t max_layers) {
  *this = CellTablePages{};
  // Parsed from copies, never through the mapping: the whole sections from a
  // file (checked here; the copies go when open returns), their headers over
  // a link (each cell is checked as it is read).
  package::Span vis, imp, index;
  std::vector<uint8_t> vb, ib, xb;
  core::Status st = core::Status::Ok;
  for (auto [tag, span, b] : {std::tuple{package::kSectionVisibility, &vis, &vb},
                              std::tuple{package::kSectionImpostors, &imp, &ib},
                              std::tuple{package::kSectionCellTableIndex, &index, &xb}})
    if ((st = tableSection(reader, source, tag, *span, err, b)) != core::Status::Ok) return st;
  try {
    for (auto [s, b, head] : {std::tuple{&index, &xb, 8}, std::tuple{&vis, &vb, 8}, std::tuple{&imp, &ib, 20}}) {
      if (!source) break;
      source->ensure(s->offset, std::min<uint64_t>(s->size, head));
      if ((st = reader.copy(*s, *b, err, size_t(head))) != core::Status::Ok) return st;
    }
  } catch (const core::Error& e) {
    err = e.what();
    return e.status();
  }
  const package::Span vc{vb.data(), vb.size(), vis.offset}, ic{ib.data(), ib.size(), imp.offset};
  if (source) {
    streets_ = &streets;
    name_ = reader.name();
    blocks_ = blocks;
    blobs_ = reader.blobCount();
    cells_ = streets.cellCount();
    max_layers_ = max_layers;
    vis_ = vis;
    imp_ = imp;
    st = openLazy(reader, vc, ic, index, xb, err);
  } else {
    st = check(reader, streets, blocks, vc, ic, index, xb, err);
  }
  if (st != core::Status::Ok) return st;
  cache_ = std::make_unique<PageCache>(reader, pages, page_bytes, source);
  t_index_ = cache_->addTable(index.data + graph::kCellTableIndexHeader, streets.cellCount(),
                              graph::kCellTableIndexEntry);
  t_vis_ = cache_->addTable(vis.data, vis.size, 1);
  t_imp_ = cache_->addTable(imp.data, imp.size, 1);
  return core::Status::Ok;
}

// `head` holds the index's first bytes (all of them, or its header).
core::Status CellTablePages::checkIndexHeader(const package::PackageReader& reader, uint32_t cells,
                                              const package::Span& index, const std::vector<uint8_t>& head,
                                              std::string& err) const {
  const uint64_t want = graph::kCellTableIndexHeader + uint64_t(cells) * graph::kCellTableIndexEntry;
  const uint32_t version = head.size() >= 4 ? at<uint32_t>(head.data()) : 0;
  if (index.size != want || head.size() < 8 || version != graph::kCellTableIndexVersion ||
      at<uint32_t>(head.data() + 4) != cells) {
    err = reader.name() + ": cell table index CTIX at offset " + std::to_string(index.offset) + ": version " +
          std::to_string(version) + ", " + std::to_string(index.size) + " bytes; a version 1 index of " +
          std::to_string(cells) + " cells has " + std::to_string(want);
    return core::Status::Corrupt;
  }
  return core::Status::Ok;
}

// The headers only (the index's, PVSA's, IMPO's): cells are checked as read.
core::Status CellTablePages::openLazy(const package::PackageReader& reader, const package::Span& vis,
                                      const package::Span& imp, const package::Span& index,
                                      const std::vector<uint8_t>& index_head, std::string& err) {
  const core::Status st = checkIndexHeader(reader, cells_, index, index_head, err);
  if (st != core::Status::Ok) return st;
  try {
    core::ByteReader rv(vis.data, vis.size, "visibility section PVSA", vis.offset);
    core::ByteReader ri(imp.data, imp.size, "impostor section IMPO", imp.offset);
    parseHeaders(rv, ri, cells_);
  } catch (const core::Error& e) {
    err = e.what();
    return e.status();
  }
  return core::Status::Ok;
}

// A cell's records end where the next cell's start (the index says so, and
// the whole check holds it to that); the last cell's at its section's end.
void CellTablePages::checkCell(uint32_t cell) const {
  try {
    checkCellRecords(cell);
  } catch (const core::Error& e) {
    throw core::Error(e.status(), name_ + ": " + e.what());
  }
}

void CellTablePages::checkCellRecords(uint32_t cell) const {
  thread_local std::vector<uint8_t> bytes;
  thread_local graph::CellVisibility v;
  thread_local graph::CellImpostors c;
  for (int which = 0; which < 2; ++which) {
    const package::Span& s = which ? imp_ : vis_;
    const uint64_t b = entry(cell, which), e = cell + 1 < cells_ ? entry(cell + 1, which) : s.size;
    const char* name = which ? "impostor section IMPO" : "visibility section PVSA";
    if (e < b || e > s.size)
      throw core::Error(core::Status::Corrupt, std::string("cell table index CTIX: cell ") + std::to_string(cell) +
                                                   "'s records in " + name + " end before they start or past the section");
    bytes.resize(size_t(e - b));
    cache_->readRange(which ? t_imp_ : t_vis_, b, uint32_t(e - b), bytes.data());
    core::ByteReader r(bytes.data(), bytes.size(), name, s.offset + b);
    if (which == 0) {
      graph::parseCellVisibility(r, blocks_, v);
    } else {
      graph::parseCellImpostors(r, blocks_, blobs_, streets_->halfedge(cell).length, c);
      if (c.layered.size() + c.single.size() > max_layers_)
        r.fail("cell " + std::to_string(cell) + " has more impostor layers than the header's pool sizing says");
    }
    if (cell + 1 < cells_ && r.remaining() != 0) r.fail("cell " + std::to_string(cell) + "'s records end early");
  }
}

// The whole parse's checks a cell at a time, and the index against where
// each cell's records start.
core::Status CellTablePages::check(const package::PackageReader& reader, const graph::GraphSource& streets,
                                   uint32_t blocks, const package::Span& vis, const package::Span& imp,
                                   const package::Span& index, const std::vector<uint8_t>& index_bytes,
                                   std::string& err) {
  const uint32_t cells = streets.cellCount();
  if (const core::Status st = checkIndexHeader(reader, cells, index, index_bytes, err); st != core::Status::Ok)
    return st;
  try {
    core::ByteReader rv(vis.data, vis.size, "visibility section PVSA", vis.offset);
    core::ByteReader ri(imp.data, imp.size, "impostor section IMPO", imp.offset);
    parseHeaders(rv, ri, cells);
    graph::CellVisibility v;
    graph::CellImpostors c;
    for (uint32_t cell = 0; cell < cells; ++cell) {
      const uint8_t* e = index_bytes.data() + graph::kCellTableIndexHeader + size_t(cell) * graph::kCellTableIndexEntry;
      if (at<uint64_t>(e) != rv.pos() || at<uint64_t>(e + 8) != ri.pos()) {
        err = reader.name() + ": cell table index CTIX at offset " +
              std::to_string(index.offset + uint64_t(e - index_bytes.data())) +
              ": cell " + std::to_string(cell) + " does not point where its records start";
        return core::Status::Corrupt;
      }
      graph::parseCellVisibility(rv, blocks, v);
      graph::parseCellImpostors(ri, blocks, reader.blobCount(), streets.halfedge(cell).length, c);
      max_layers_ = std::max<uint32_t>(max_layers_, static_cast<uint32_t>(c.layered.size() + c.single.size()));
    }
  } catch (const core::Error& e) {
    err = reader.name() + ": " + e.what();
    return e.status();
  }
  return core::Status::Ok;
}

uint64_t CellTablePages::entry(uint32_t cell, int which) const {
  uint8_t e[graph::kCellTableIndexEntry];
  cache_->read(t_index_, cell, e);
  return at<uint64_t>(e + 8 * which);
}

void CellTablePages::layers(uint32_t cell, LayerInfo* out, uint32_t cap, uint32_t* layered, uint32_t* single) const {
  if (streets_) checkCell(cell);
  uint64_t off = entry(cell, 1);
  uint32_t written = 0;
  for (uint32_t* count : {layered, single}) {
    uint32_t n = 0;
    cache_->readRange(t_imp_, off, 4, &n);
    off += 4;
    *count = 0;
    for (uint32_t i = 0; i < n; ++i) {
      uint8_t b[kLayerBytes];
      cache_->readRange(t_imp_, off, kLayerBytes, b);
      off += kLayerBytes + 4ull * at<uint32_t>(b + 20);
      if (written == cap) continue;
      LayerInfo& l = out[written++];
      l.blob = at<uint32_t>(b);
      l.triangles = at<uint32_t>(b + 4);
      l.vertices = at<uint32_t>(b + 8);
      l.texture_width = at<uint16_t>(b + 12);
      l.texture_height = at<uint16_t>(b + 14);
      l.run_from_m = at<float>(b + 16);
      ++*count;
    }
  }
}

float CellTablePages::coverage(uint32_t cell, uint32_t block) const {
  if (streets_) checkCell(cell);
  const uint64_t off = entry(cell, 0);
  uint32_t k = 0;
  cache_->readRange(t_vis_, off, 4, &k);
  uint32_t lo = 0, hi = k;  // entries ascending by block
  while (lo < hi) {
    const uint32_t mid = lo + (hi - lo) / 2;
    uint8_t e[8];
    cache_->readRange(t_vis_, off + 4 + 8ull * mid, 8, e);
    const uint32_t b = at<uint32_t>(e);
    if (b == block) return at<float>(e + 4);
    if (b < block) lo = mid + 1;
    else hi = mid;
  }
  return 0.f;
}

}  // namespace blvd::stream
