// A package's street graph read through a PageCache: the GRPH half-edges and
// points, the CELL lists and the SIDX segment grid stay in the file and come in
// a page at a time, so a runtime holds the same bytes of graph for a town and
// for a region (docs/decisions/0013).
//
// open() locates the tables and then reads every record once through the
// cache, checking what parseGraph/parseCells check (indices in range, finite
// points, offsets that do not decrease), so that no later read can hand out an
// index past its table. A package without SIDX (format 3.0) gets its grid
// built in memory from the paged tables: it grows with the city.
//
// With a PageSource (a package on a server whose tables arrive a page at a
// time) open reads only the tables' counts, and each read checks its record
// instead (the same checks): a bad one throws core::Error(Corrupt) naming the
// record and its offset, as does a page the source cannot bring (Unavailable).
#pragma once
#include <cstdint>
#include <memory>
#include <string>

#include "core/status.h"
#include "graph/graph_source.h"
#include "package/reader.h"
#include "stream/page_cache.h"

namespace blvd::stream {

struct PagedGraphDesc {
  uint32_t pages = 0;       // cache pages; 0: kDefaultPages
  uint32_t page_bytes = 0;  // 0: kDefaultPageBytes
  static constexpr uint32_t kDefaultPages = 256;
  static constexpr uint32_t kDefaultPageBytes = 2048;
};

class PagedGraph final : public graph::GraphSource {
 public:
  // Corrupt naming the file, section and offset when a table is cut short or a
  // record is out of range. The reader must outlive the graph.
  core::Status open(const package::PackageReader& reader, std::string& err, const PagedGraphDesc& desc = {},
                    const PageSource* source = nullptr);

  uint32_t cellCount() const override { return halfedges_; }
  uint32_t pointCount() const override { return points_; }
  graph::HalfEdge halfedge(uint32_t h) const override;
  glm::dvec2 point(uint32_t i) const override;
  void listBounds(graph::CellList list, uint32_t h, uint32_t* first, uint32_t* last) const override;
  uint32_t item(graph::CellList list, uint32_t i) const override;
  void segmentsNear(double x, double y, double r, EntryFn fn, void* ctx) const override;
  graph::GridShape gridShape() const override { return grid_ ? grid_->shape() : stored_.shape; }
  uint32_t gridEntryCount() const override;

  uint32_t vertexCount() const { return vertices_; }
  uint32_t faceCount() const { return faces_; }
  // Bytes held: the cache, plus a grid built in memory for a package without one.
  uint64_t bytes() const;
  PageCacheStats stats() const { return cache_ ? cache_->stats() : PageCacheStats{}; }

 private:
  struct Lists {
    uint32_t offsets = 0, items = 0;  // page cache table ids
    uint32_t count = 0;               // items
  };
  core::Status locate(const package::PackageReader& reader, const PageSource* source, std::string& err);
  core::Status openGrid(const package::PackageReader& reader, const PageSource* source, package::Span& sidx,
                        std::string& err);
  [[noreturn]] void bad(const uint8_t* table, uint64_t record, uint64_t i, const std::string& why) const;
  void check() const;  // every record; throws core::Error(Corrupt) for a bad one
  void checkGrid() const;
  graph::SegmentGrid::Entry gridEntry(uint32_t i) const;
  const Lists& lists(graph::CellList l) const { return lists_[static_cast<int>(l)]; }
  uint32_t u32(uint32_t table, uint32_t i) const;

  std::unique_ptr<PageCache> cache_;
  uint32_t vertices_ = 0, halfedges_ = 0, faces_ = 0, points_ = 0;
  uint32_t t_halfedges_ = 0, t_points_ = 0, t_grid_offsets_ = 0, t_grid_entries_ = 0;
  Lists lists_[3];
  graph::StoredGrid stored_;
  std::unique_ptr<graph::SegmentGrid> grid_;  // built when the package has no SIDX
  // Where the tables start in the reserved range, found by locate() before the cache exists.
  const uint8_t* at_halfedges_ = nullptr;
  const uint8_t* at_points_ = nullptr;
  const uint8_t* at_lists_[3][2] = {};
  // File offset of a byte of the GRPH or CELL section (for messages).
  uint64_t fileOffset(const uint8_t* p) const;
  package::Span grph_, cell_;
  std::string name_;  // the package's, for messages
};

}  // namespace blvd::stream
