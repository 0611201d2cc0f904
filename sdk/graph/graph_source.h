// The read side of a street graph that the runtime and the tracker use: one
// half-edge, one polyline point, one cell's lists, the segments near a point.
// Two sources implement it: `MemoryGraph`, over a whole `StreetGraph` in memory
// (the bake, the tools, the tests), and `stream::PagedGraph`, which pages a
// package's graph tables through a fixed cache so that what a vehicle holds
// does not grow with the city.
//
// Everything is returned by value: a paged source may evict the page an
// earlier answer came from, so callers never hold references into it.
#pragma once
#include <cstddef>
#include <cstdint>
#include <iterator>

#include <glm/vec2.hpp>

#include "graph/segment_grid.h"
#include "graph/street_graph.h"

namespace blvd::graph {

enum class CellList : uint8_t { Successors, Predecessors, LocalBlocks };

class GraphSource {
 public:
  virtual ~GraphSource() = default;

  virtual uint32_t cellCount() const = 0;
  virtual uint32_t pointCount() const = 0;
  // h < cellCount(), i < pointCount(): callers check, as they would index an array.
  virtual HalfEdge halfedge(uint32_t h) const = 0;
  virtual glm::dvec2 point(uint32_t i) const = 0;
  // The items of cell h's list are item(list, first) .. item(list, last - 1).
  virtual void listBounds(CellList list, uint32_t h, uint32_t* first, uint32_t* last) const = 0;
  virtual uint32_t item(CellList list, uint32_t i) const = 0;

  // Calls fn(entry, ctx) for each grid entry in the grid cells overlapping the
  // square of half-size r around (x, y) (graph/segment_grid.h has the rules).
  using EntryFn = void (*)(const SegmentGrid::Entry&, void* ctx);
  virtual void segmentsNear(double x, double y, double r, EntryFn fn, void* ctx) const = 0;
  virtual GridShape gridShape() const = 0;  // its extent is the box of every street point
  virtual uint32_t gridEntryCount() const = 0;
  template <class Fn>
  void forSegmentsNear(double x, double y, double r, Fn&& fn) const {
    segmentsNear(x, y, r, [](const SegmentGrid::Entry& e, void* c) { (*static_cast<Fn*>(c))(e); }, &fn);
  }

  uint32_t endVertex(uint32_t h) const { return halfedge(halfedge(h).twin).origin; }

  // A cell's list, for range-for: each item is read when dereferenced.
  class List {
   public:
    class It {
     public:
      using iterator_category = std::input_iterator_tag;
      using value_type = uint32_t;
      using difference_type = std::ptrdiff_t;
      using pointer = void;
      using reference = uint32_t;
      It(const GraphSource* g, CellList l, uint32_t i) : g_(g), l_(l), i_(i) {}
      uint32_t operator*() const { return g_->item(l_, i_); }
      It& operator++() { ++i_; return *this; }
      bool operator!=(const It& o) const { return i_ != o.i_; }
      bool operator==(const It& o) const { return i_ == o.i_; }

     private:
      const GraphSource* g_;
      CellList l_;
      uint32_t i_;
    };
    It begin() const { return It(g_, l_, first_); }
    It end() const { return It(g_, l_, last_); }
    uint32_t size() const { return last_ - first_; }

   private:
    friend class GraphSource;
    List(const GraphSource* g, CellList l, uint32_t h) : g_(g), l_(l) { g->listBounds(l, h, &first_, &last_); }
    const GraphSource* g_;
    CellList l_;
    uint32_t first_ = 0, last_ = 0;
  };
  List successors(uint32_t h) const { return List(this, CellList::Successors, h); }
  List predecessors(uint32_t h) const { return List(this, CellList::Predecessors, h); }
  List localBlocks(uint32_t h) const { return List(this, CellList::LocalBlocks, h); }
};

// A whole StreetGraph in memory, with its segment grid built at construction.
// The graph must outlive it.
class MemoryGraph final : public GraphSource {
 public:
  explicit MemoryGraph(const StreetGraph& g, double grid_cell_m = 0);

  uint32_t cellCount() const override { return static_cast<uint32_t>(g_.halfedges.size()); }
  uint32_t pointCount() const override { return static_cast<uint32_t>(g_.points.size()); }
  HalfEdge halfedge(uint32_t h) const override { return g_.halfedges[h]; }
  glm::dvec2 point(uint32_t i) const override { return g_.points[i]; }
  void listBounds(CellList list, uint32_t h, uint32_t* first, uint32_t* last) const override;
  uint32_t item(CellList list, uint32_t i) const override { return csr(list).items[i]; }
  void segmentsNear(double x, double y, double r, EntryFn fn, void* ctx) const override;
  GridShape gridShape() const override { return grid_.shape(); }
  uint32_t gridEntryCount() const override { return static_cast<uint32_t>(grid_.entryCount()); }

  const StreetGraph& graph() const { return g_; }
  const SegmentGrid& grid() const { return grid_; }
  size_t bytes() const { return grid_.bytes(); }  // besides the graph it reads

 private:
  const Csr& csr(CellList l) const;
  const StreetGraph& g_;
  SegmentGrid grid_;
};

// Unit direction of cell h's polyline at its start or end, as
// cellDirection(const StreetGraph&, ...) gives it.
glm::dvec2 cellDirection(const GraphSource& g, uint32_t h, bool at_end);

// How far outside the box of its streets a pose still counts as on the map: a
// vehicle a block or two past the baked area still sees it; farther out a pose
// is refused (host poses) or reported off the map (tracking), never given the
// nearest cell, which could lie hundreds of kilometres away. blvd.h: BLVD_MAP_MARGIN_M.
inline constexpr double kMapMarginM = 250.0;

// How far (x, y) lies outside the box of g's streets (0 inside it).
double outsideStreets(const GraphSource& g, double x, double y);
inline bool onMap(const GraphSource& g, double x, double y) { return outsideStreets(g, x, y) <= kMapMarginM; }

}  // namespace blvd::graph
