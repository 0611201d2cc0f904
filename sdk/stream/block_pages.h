// A package's block table (BLCK) read a record at a time through a page cache,
// for the runtime: what it holds of the table is the cache, whatever the
// city's size (docs/decisions/0013).
#pragma once
#include <cstdint>
#include <memory>
#include <string>

#include "core/status.h"
#include "graph/block_table.h"
#include "package/reader.h"
#include "stream/page_cache.h"

namespace blvd::stream {

class BlockPages {
 public:
  static constexpr uint32_t kMaxRecordBytes = 1024;  // at most a page of the cache
  // Checks every record as parseBlocks does, in one pass, and keeps nothing
  // of the table but the cache. Corrupt naming the file and offset; NotFound
  // without a BLCK section. The reader must outlive this.
  // With a source (table pages that arrive over the link) only the table's
  // shape is read here, and record() checks each record it reads instead,
  // throwing core::Error(Corrupt) naming it.
  core::Status open(const package::PackageReader& reader, uint32_t pages, uint32_t page_bytes, std::string& err,
                    const PageSource* source = nullptr);

  uint32_t count() const { return shape_.count; }
  graph::BlockRecord record(uint32_t b) const;  // b < count()

  uint64_t bytes() const { return sizeof(*this) + (cache_ ? cache_->bytes() : 0); }
  PageCacheStats stats() const { return cache_ ? cache_->stats() : PageCacheStats{}; }

 private:
  std::unique_ptr<PageCache> cache_;
  graph::BlockTableShape shape_;
  uint32_t blobs_ = 0, table_ = 0;
  uint64_t records_offset_ = 0;  // in the file, for messages
  std::string name_;
};

}  // namespace blvd::stream
