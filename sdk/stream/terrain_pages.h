// A package's terrain tiles (TERR, graph/terrain_table.h): the tree's layout
// and its records read through a page cache, so that what a runtime holds of
// a region's terrain table is the cache, whatever the region's size.
#pragma once
#include <cstdint>
#include <memory>
#include <string>

#include "core/status.h"
#include "graph/terrain_table.h"
#include "package/reader.h"
#include "stream/page_cache.h"

namespace blvd::stream {

class TerrainPages {
 public:
  static constexpr uint32_t kPages = 8, kPageBytes = 2048;  // 1,024 records
  // Reads the header and checks every record (a package over the link: only
  // the header here, each record as record() reads it). Corrupt naming the
  // file and offset; NotFound without a TERR section. The reader must
  // outlive this.
  core::Status open(const package::PackageReader& reader, std::string& err, const PageSource* source = nullptr);

  const graph::TerrainLayout& layout() const { return layout_; }
  // Record i (< layout().tiles()); throws core::Error(Corrupt) naming the
  // file offset for one that breaks the rules (read over the link unchecked).
  graph::TerrainRecord record(uint32_t i) const;

  uint64_t bytes() const { return sizeof(*this) + (cache_ ? cache_->bytes() : 0); }

 private:
  std::string check(uint32_t i, graph::TerrainRecord& r) const;
  std::unique_ptr<PageCache> cache_;
  graph::TerrainLayout layout_;
  uint32_t blobs_ = 0, table_ = 0;
  uint64_t records_offset_ = 0;  // in the file, for messages
  std::string name_;
};

}  // namespace blvd::stream
