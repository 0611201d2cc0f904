#include "stream/block_pages.h"

#include <vector>

namespace blvd::stream {

core::Status BlockPages::open(const package::PackageReader& reader, uint32_t pages, uint32_t page_bytes,
                              std::string& err) {
  *this = BlockPages{};
  package::Span s;
  core::Status st = reader.checkedSection(package::kSectionBlocks, s, err);
  if (st != core::Status::Ok) return st;
  blobs_ = reader.blobCount();
  try {
    shape_ = graph::parseBlockTableShape(s.data, s.size, s.offset);
    if (shape_.record_size > kMaxRecordBytes) {
      reader.dropPages(s);
      err = reader.name() + ": block section BLCK: records of " + std::to_string(shape_.record_size) +
            " bytes; this build reads records of up to " + std::to_string(kMaxRecordBytes);
      return core::Status::Unsupported;
    }
    graph::BlockRecord b;
    for (uint32_t i = 0; i < shape_.count; ++i) {
      const size_t at = shape_.records_at + size_t(i) * shape_.record_size;
      const std::string why = graph::parseBlockRecord(s.data + at, blobs_, b);
      if (!why.empty()) {
        err = reader.name() + ": block section BLCK at offset " + std::to_string(s.offset + at) + ": block " +
              std::to_string(i) + ": " + why;
        st = core::Status::Corrupt;
        break;
      }
    }
  } catch (const core::Error& e) {
    err = reader.name() + ": " + e.what();
    st = e.status();
  }
  reader.dropPages(s);
  if (st != core::Status::Ok) return st;
  cache_ = std::make_unique<PageCache>(reader, pages, page_bytes);
  table_ = cache_->addTable(s.data + shape_.records_at, shape_.count, shape_.record_size);
  return core::Status::Ok;
}

graph::BlockRecord BlockPages::record(uint32_t b) const {
  // A record is at most a page (a later minor version's larger one is read in part).
  uint8_t rec[kMaxRecordBytes];
  cache_->readRange(table_, b, 1, rec);
  graph::BlockRecord r;
  graph::parseBlockRecord(rec, blobs_, r);  // checked at open
  return r;
}

}  // namespace blvd::stream
