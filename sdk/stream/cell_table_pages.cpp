#include "stream/cell_table_pages.h"

#include <algorithm>
#include <cstring>

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

}  // namespace

core::Status CellTablePages::open(const package::PackageReader& reader, const graph::GraphSource& streets,
                                  uint32_t blocks, uint32_t pages, uint32_t page_bytes, std::string& err) {
  *this = CellTablePages{};
  package::Span vis, imp, index;
  for (auto [tag, span] : {std::pair{package::kSectionVisibility, &vis}, std::pair{package::kSectionImpostors, &imp},
                           std::pair{package::kSectionCellTableIndex, &index}}) {
    const core::Status st = reader.checkedSection(tag, *span, err);
    if (st != core::Status::Ok) return st;
  }
  const core::Status st = check(reader, streets, blocks, vis, imp, index, err);
  reader.dropPages(vis);
  reader.dropPages(imp);
  reader.dropPages(index);
  if (st != core::Status::Ok) return st;
  cache_ = std::make_unique<PageCache>(reader, pages, page_bytes);
  t_index_ = cache_->addTable(index.data + graph::kCellTableIndexHeader, streets.cellCount(),
                              graph::kCellTableIndexEntry);
  t_vis_ = cache_->addTable(vis.data, vis.size, 1);
  t_imp_ = cache_->addTable(imp.data, imp.size, 1);
  return core::Status::Ok;
}

// The whole parse's checks a cell at a time, and the index against where
// each cell's records start.
core::Status CellTablePages::check(const package::PackageReader& reader, const graph::GraphSource& streets,
                                   uint32_t blocks, const package::Span& vis, const package::Span& imp,
                                   const package::Span& index, std::string& err) {
  const uint32_t cells = streets.cellCount();
  const uint64_t want = graph::kCellTableIndexHeader + uint64_t(cells) * graph::kCellTableIndexEntry;
  if (index.size != want || at<uint32_t>(index.data) != graph::kCellTableIndexVersion ||
      at<uint32_t>(index.data + 4) != cells) {
    err = reader.name() + ": cell table index CTIX at offset " + std::to_string(index.offset) + ": version " +
          std::to_string(index.size >= 4 ? at<uint32_t>(index.data) : 0) + ", " + std::to_string(index.size) +
          " bytes; a version 1 index of " + std::to_string(cells) + " cells has " + std::to_string(want);
    return core::Status::Corrupt;
  }
  try {
    core::ByteReader rv(vis.data, vis.size, "visibility section PVSA", vis.offset);
    core::ByteReader ri(imp.data, imp.size, "impostor section IMPO", imp.offset);
    graph::CellTables display;
    graph::parseVisibilityHeader(rv, cells);
    graph::parseImpostorsHeader(ri, cells, display);
    graph::CellVisibility v;
    graph::CellImpostors c;
    for (uint32_t cell = 0; cell < cells; ++cell) {
      const uint8_t* e = index.data + graph::kCellTableIndexHeader + size_t(cell) * graph::kCellTableIndexEntry;
      if (at<uint64_t>(e) != rv.pos() || at<uint64_t>(e + 8) != ri.pos()) {
        err = reader.name() + ": cell table index CTIX at offset " + std::to_string(index.offset + (e - index.data)) +
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
