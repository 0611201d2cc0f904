// A fixed cache of pages of a package's tables: fixed-size records read by
// index, a page at a time, into slots carved when the cache is made. What a
// city's tables cost a vehicle is then the cache's size, whatever the city's:
// a page that is not cached is copied from the package (and the file's pages
// it came from are dropped from the process), evicting the least recently used
// page of its set.
//
// Four-way set-associative, keyed by (table, page). Thread-safe: one mutex
// around lookup and copy, so the render thread, the loader threads and the
// tracker may read the same tables; a record is copied out under the lock.
//
// A package on a server (remote/remote_package.h) may not hold a page yet:
// with a PageSource, a page missing from the cache is first made present in
// the file (outside the lock: other readers go on), which may wait for the
// link or throw core::Error. A record past its table's end throws Corrupt.
#pragma once
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "package/reader.h"

namespace blvd::stream {

struct PageCacheStats {
  uint64_t hits = 0, misses = 0;
};

// Makes file bytes readable through the reader's mapping before a page is
// copied from it, or throws core::Error (Unavailable, Corrupt, Io).
class PageSource {
 public:
  virtual void ensure(uint64_t offset, uint64_t size) const = 0;

 protected:
  ~PageSource() = default;
};

// Where a table section lies: CRC-checked whole without a source (its bytes
// read, and kept in `bytes` when given); with one, unchecked here (each page
// is checked as the source brings it, `bytes` untouched). NotFound when the
// package has no such section.
core::Status tableSection(const package::PackageReader& reader, const PageSource* source, uint32_t tag,
                          package::Span& out, std::string& err, std::vector<uint8_t>* bytes = nullptr);

class PageCache {
 public:
  static constexpr uint32_t kWays = 4;

  // `pages` (rounded up to a multiple of kWays, at least kWays) slots of
  // `page_bytes` each. The reader must outlive the cache.
  PageCache(const package::PackageReader& reader, uint32_t pages, uint32_t page_bytes,
            const PageSource* source = nullptr);

  // A table of `count` records of `record_bytes` each (at most a page) at
  // `data` (inside the reader's mapping). Returns its id for read().
  uint32_t addTable(const uint8_t* data, uint64_t count, uint32_t record_bytes);

  // Copies record i of table t (i < its count: callers check) into out.
  void read(uint32_t t, uint32_t i, void* out) const;
  // Copies records [first, first + n) of table t (within its count) into out,
  // across pages: for a table of bytes, a variable-length record.
  void readRange(uint32_t t, uint64_t first, uint32_t n, void* out) const;

  uint64_t bytes() const { return slots_.size() + tags_.size() * sizeof(Tag) + tables_.size() * sizeof(Table); }
  uint32_t pageBytes() const { return page_bytes_; }
  PageCacheStats stats() const;

 private:
  struct Table {
    const uint8_t* data;
    uint64_t count;
    uint32_t record, per_page;
  };
  struct Tag {
    uint64_t key = ~0ull;  // (table << 32) | page
    uint64_t used = 0;     // tick of the last read
  };
  const uint8_t* load(uint32_t t, uint32_t page, size_t slot) const;
  // Cached or loaded; `lock` holds mu_ (released while the source fills the page).
  const uint8_t* cached(uint32_t t, uint32_t page, std::unique_lock<std::mutex>& lock) const;
  const uint8_t* find(uint64_t key, size_t set, size_t* victim) const;  // under mu_
  void ensurePage(uint32_t t, uint32_t page) const;
  [[noreturn]] void pastEnd(uint32_t t, uint64_t i) const;

  const package::PackageReader& reader_;
  const PageSource* source_;
  uint32_t page_bytes_, sets_;
  std::vector<Table> tables_;
  mutable std::mutex mu_;
  mutable std::vector<uint8_t> slots_;
  mutable std::vector<Tag> tags_;
  mutable uint64_t tick_ = 0;
  mutable PageCacheStats stats_;
};

}  // namespace blvd::stream
