#include "stream/page_cache.h"

#include <algorithm>
#include <cstring>

namespace blvd::stream {

PageCache::PageCache(const package::PackageReader& reader, uint32_t pages, uint32_t page_bytes)
    : reader_(reader), page_bytes_(std::max<uint32_t>(page_bytes, 64)) {
  sets_ = std::max<uint32_t>(1, (pages + kWays - 1) / kWays);
  slots_.resize(size_t(sets_) * kWays * page_bytes_);
  tags_.resize(size_t(sets_) * kWays);
}

uint32_t PageCache::addTable(const uint8_t* data, uint32_t count, uint32_t record_bytes) {
  const uint32_t per_page = std::max<uint32_t>(1, page_bytes_ / record_bytes);
  tables_.push_back(Table{data, count, record_bytes, per_page});
  return static_cast<uint32_t>(tables_.size() - 1);
}

const uint8_t* PageCache::load(uint32_t t, uint32_t page, size_t slot) const {
  const Table& tb = tables_[t];
  const uint32_t first = page * tb.per_page;
  const uint32_t n = std::min(tb.per_page, tb.count - first);
  uint8_t* dst = &slots_[slot * page_bytes_];
  package::Span src{tb.data + size_t(first) * tb.record, size_t(n) * tb.record, 0};
  std::memcpy(dst, src.data, src.size);
  reader_.dropEnclosingPages(src);  // the copy holds it now
  return dst;
}

void PageCache::read(uint32_t t, uint32_t i, void* out) const {
  const Table& tb = tables_[t];
  const uint32_t page = i / tb.per_page;
  const uint64_t key = (uint64_t(t) << 32) | page;
  const size_t set = size_t((key * 0x9E3779B97F4A7C15ull) >> 40) % sets_;
  std::lock_guard<std::mutex> lock(mu_);
  ++tick_;
  size_t victim = set * kWays;
  const uint8_t* base = nullptr;
  for (size_t w = set * kWays; w < (set + 1) * kWays; ++w) {
    if (tags_[w].key == key) {
      base = &slots_[w * page_bytes_];
      tags_[w].used = tick_;
      ++stats_.hits;
      break;
    }
    if (tags_[w].used < tags_[victim].used) victim = w;
  }
  if (!base) {
    ++stats_.misses;
    base = load(t, page, victim);
    tags_[victim] = Tag{key, tick_};
  }
  std::memcpy(out, base + size_t(i - page * tb.per_page) * tb.record, tb.record);
}

PageCacheStats PageCache::stats() const {
  std::lock_guard<std::mutex> lock(mu_);
  return stats_;
}

}  // namespace blvd::stream
