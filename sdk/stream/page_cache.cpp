#include "stream/page_cache.h"

#include <algorithm>
#include <cstring>
#include <string>

#include "core/status.h"

namespace blvd::stream {

core::Status tableSection(const package::PackageReader& reader, const PageSource* source, uint32_t tag,
                          package::Span& out, std::string& err, std::vector<uint8_t>* bytes) {
  if (!source && bytes) {
    package::Span copy;
    const core::Status st = reader.checkedCopy(tag, *bytes, copy, err);
    if (st == core::Status::Ok) out = reader.section(tag);
    return st;
  }
  if (!source) return reader.checkedSection(tag, out, err);
  out = reader.section(tag);
  if (out.data) return core::Status::Ok;
  err = reader.name() + ": no section " + package::tagToString(tag);
  return core::Status::NotFound;
}

PageCache::PageCache(const package::PackageReader& reader, uint32_t pages, uint32_t page_bytes,
                     const PageSource* source)
    : reader_(reader), source_(source), page_bytes_(std::max<uint32_t>(page_bytes, 64)) {
  sets_ = std::max<uint32_t>(1, (pages + kWays - 1) / kWays);
  slots_.resize(size_t(sets_) * kWays * page_bytes_);
  tags_.resize(size_t(sets_) * kWays);
}

uint32_t PageCache::addTable(const uint8_t* data, uint64_t count, uint32_t record_bytes) {
  if (record_bytes == 0 || record_bytes > page_bytes_)
    throw core::Error(core::Status::Internal, "page cache: a record of " + std::to_string(record_bytes) +
                                                  " bytes does not fit a page of " + std::to_string(page_bytes_));
  const uint32_t per_page = page_bytes_ / record_bytes;
  tables_.push_back(Table{data, count, record_bytes, per_page});
  return static_cast<uint32_t>(tables_.size() - 1);
}

const uint8_t* PageCache::load(uint32_t t, uint32_t page, size_t slot) const {
  const Table& tb = tables_[t];
  const uint64_t first = uint64_t(page) * tb.per_page;
  const uint64_t n = std::min<uint64_t>(tb.per_page, tb.count - first);
  uint8_t* dst = &slots_[slot * page_bytes_];
  // Read, not copied from the mapping: a file truncated since open is an
  // error here, not a SIGBUS (package/reader.h).
  std::string err;
  const core::Status st =
      reader_.read(reader_.offsetOf(tb.data) + first * tb.record, size_t(n) * tb.record, dst, err);
  if (st != core::Status::Ok) throw core::Error(st, err);
  return dst;
}

const uint8_t* PageCache::find(uint64_t key, size_t set, size_t* victim) const {
  *victim = set * kWays;
  for (size_t w = set * kWays; w < (set + 1) * kWays; ++w) {
    if (tags_[w].key == key) {
      tags_[w].used = tick_;
      return &slots_[w * page_bytes_];
    }
    if (tags_[w].used < tags_[*victim].used) *victim = w;
  }
  return nullptr;
}

void PageCache::ensurePage(uint32_t t, uint32_t page) const {
  const Table& tb = tables_[t];
  const uint64_t first = uint64_t(page) * tb.per_page;
  const uint64_t n = std::min<uint64_t>(tb.per_page, tb.count - first);
  source_->ensure(reader_.offsetOf(tb.data) + first * tb.record, n * tb.record);
}

const uint8_t* PageCache::cached(uint32_t t, uint32_t page, std::unique_lock<std::mutex>& lock) const {
  const uint64_t key = (uint64_t(t) << 32) | page;
  const size_t set = size_t((key * 0x9E3779B97F4A7C15ull) >> 40) % sets_;
  ++tick_;
  size_t victim;
  if (const uint8_t* p = find(key, set, &victim)) {
    ++stats_.hits;
    return p;
  }
  ++stats_.misses;
  if (source_) {
    lock.unlock();
    ensurePage(t, page);  // may wait for the link, or throw
    lock.lock();
    if (const uint8_t* p = find(key, set, &victim)) return p;  // another reader loaded it meanwhile
  }
  tags_[victim] = Tag{};  // a read that fails leaves the slot empty, not the old page's
  const uint8_t* base = load(t, page, victim);
  tags_[victim] = Tag{key, tick_};
  return base;
}

void PageCache::pastEnd(uint32_t t, uint64_t i) const {
  throw core::Error(core::Status::Corrupt, reader_.name() + ": table at file offset " +
                                               std::to_string(reader_.offsetOf(tables_[t].data)) + ": record " +
                                               std::to_string(i) + " is past its " +
                                               std::to_string(tables_[t].count) + " records");
}

void PageCache::read(uint32_t t, uint32_t i, void* out) const {
  const Table& tb = tables_[t];
  if (i >= tb.count) pastEnd(t, i);
  const uint32_t p = i / tb.per_page;
  std::unique_lock<std::mutex> lock(mu_);
  std::memcpy(out, cached(t, p, lock) + size_t(i - uint64_t(p) * tb.per_page) * tb.record, tb.record);
}

void PageCache::readRange(uint32_t t, uint64_t first, uint32_t n, void* out) const {
  const Table& tb = tables_[t];
  if (first > tb.count || n > tb.count - first) pastEnd(t, first + n);
  uint8_t* dst = static_cast<uint8_t*>(out);
  std::unique_lock<std::mutex> lock(mu_);
  while (n > 0) {
    const uint64_t p = first / tb.per_page, in = first - p * tb.per_page;
    const uint32_t take = static_cast<uint32_t>(std::min<uint64_t>(n, tb.per_page - in));
    std::memcpy(dst, cached(t, static_cast<uint32_t>(p), lock) + in * tb.record, size_t(take) * tb.record);
    dst += size_t(take) * tb.record;
    first += take;
    n -= take;
  }
}

PageCacheStats PageCache::stats() const {
  std::lock_guard<std::mutex> lock(mu_);
  return stats_;
}

}  // namespace blvd::stream
