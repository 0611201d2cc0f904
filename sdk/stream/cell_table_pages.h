// A package's per-cell visibility and impostor tables (PVSA, IMPO) read a cell
// at a time through a page cache, found by the cell table index (CTIX): what
// the runtime holds of them is the cache, whatever the city's size
// (docs/decisions/0013). The runtime needs of them only what it loads and
// draws: a cell's impostor layers and its blocks' coverage hints.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/status.h"
#include "graph/graph_source.h"
#include "package/reader.h"
#include "stream/page_cache.h"

namespace blvd::stream {

// One impostor layer of a cell as the runtime loads and draws it (the far
// blocks it stands for are the bake's and the tools' business).
struct LayerInfo {
  uint32_t blob = 0, triangles = 0, vertices = 0;
  uint16_t texture_width = 0, texture_height = 0;
  float run_from_m = 0.f;
};

class CellTablePages {
 public:
  // Checks PVSA, IMPO and CTIX in one pass: every cell's records with the
  // whole parse's checks, and that each index entry points where its cell's
  // records start. Keeps nothing of them but a cache of `pages` pages of
  // `page_bytes`. Corrupt naming the file, section and offset. The reader and
  // the graph must outlive this.
  //
  // With a source (table pages that arrive over the link) open checks the
  // index's and the tables' headers only, maxLayers() is `max_layers` (the
  // package header's pool sizing), and layers() and coverage() check the
  // cell's records with the same parse before they read them, throwing
  // core::Error(Corrupt) naming the section and offset.
  core::Status open(const package::PackageReader& reader, const graph::GraphSource& streets, uint32_t blocks,
                    uint32_t pages, uint32_t page_bytes, std::string& err, const PageSource* source = nullptr,
                    uint32_t max_layers = 0);

  // Layers of the cell with the most (layered and single together).
  uint32_t maxLayers() const { return max_layers_; }
  // The cell's layered layers into out[0 .. *layered), then its single ones
  // (at most `cap` in all; maxLayers() always suffices).
  void layers(uint32_t cell, LayerInfo* out, uint32_t cap, uint32_t* layered, uint32_t* single) const;
  // The coverage hint of `block` from `cell` (0 when the block is not in its PVS).
  float coverage(uint32_t cell, uint32_t block) const;

  uint64_t bytes() const { return sizeof(*this) + (cache_ ? cache_->bytes() : 0); }
  PageCacheStats stats() const { return cache_ ? cache_->stats() : PageCacheStats{}; }

 private:
  // `vis` and `imp` point at copies of the sections (their headers only, in
  // openLazy), `index_bytes` holds the index's; `index` is where it lies.
  core::Status check(const package::PackageReader& reader, const graph::GraphSource& streets, uint32_t blocks,
                     const package::Span& vis, const package::Span& imp, const package::Span& index,
                     const std::vector<uint8_t>& index_bytes, std::string& err);
  uint64_t entry(uint32_t cell, int which) const;  // 0: PVSA offset, 1: IMPO offset
  core::Status checkIndexHeader(const package::PackageReader& reader, uint32_t cells, const package::Span& index,
                                const std::vector<uint8_t>& head, std::string& err) const;
  core::Status openLazy(const package::PackageReader& reader, const package::Span& vis, const package::Span& imp,
                        const package::Span& index, const std::vector<uint8_t>& index_head, std::string& err);
  void checkCell(uint32_t cell) const;  // lazy: the cell's records, parsed; throws naming the file
  void checkCellRecords(uint32_t cell) const;

  std::unique_ptr<PageCache> cache_;
  uint32_t t_index_ = 0, t_vis_ = 0, t_imp_ = 0;
  uint32_t max_layers_ = 0;
  // Lazy (a source): what checkCell() needs.
  const graph::GraphSource* streets_ = nullptr;
  uint32_t blocks_ = 0, blobs_ = 0, cells_ = 0;
  package::Span vis_, imp_;
  std::string name_;
};

}  // namespace blvd::stream
