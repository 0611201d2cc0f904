#include "stream/block_pages.h"

#include <algorithm>
#include <vector>

namespace blvd::stream {

core::Status BlockPages::open(const package::PackageReader& reader, uint32_t pages, uint32_t page_bytes,
                              std::string& err, const PageSource* source) {
  *this = BlockPages{};
  // Read, never touched through the mapping: the whole table from a file
  // (every record is checked here; the copy goes when open returns), the
  // header (version, record size, count) over a link.
  package::Span s;
  std::vector<uint8_t> bytes;
  core::Status st = tableSection(reader, source, package::kSectionBlocks, s, err, &bytes);
  if (st != core::Status::Ok) return st;
  blobs_ = reader.blobCount();
  name_ = reader.name();
  try {
    if (source) source->ensure(s.offset, std::min<uint64_t>(s.size, 12));
    if (source && (st = reader.copy(s, bytes, err, 12)) != core::Status::Ok) return st;
    shape_ = graph::parseBlockTableShape(bytes.data(), s.size, s.offset);  // reads the header only
    if (shape_.record_size > kMaxRecordBytes) {
      err = reader.name() + ": block section BLCK: records of " + std::to_string(shape_.record_size) +
            " bytes; this build reads records of up to " + std::to_string(kMaxRecordBytes);
      return core::Status::Unsupported;
    }
    graph::BlockRecord b;
    for (uint32_t i = 0; !source && i < shape_.count; ++i) {
      const size_t at = shape_.records_at + size_t(i) * shape_.record_size;
      const std::string why = graph::parseBlockRecord(bytes.data() + at, blobs_, b);
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
  if (st != core::Status::Ok) return st;
  cache_ = std::make_unique<PageCache>(reader, pages, page_bytes, source);
  table_ = cache_->addTable(s.data + shape_.records_at, shape_.count, shape_.record_size);
  records_offset_ = s.offset + shape_.records_at;
  return core::Status::Ok;
}

graph::BlockRecord BlockPages::record(uint32_t b) const {
  // A record is at most a page (a later minor version's larger one is read in part).
  uint8_t rec[kMaxRecordBytes];
  cache_->readRange(table_, b, 1, rec);
  graph::BlockRecord r;
  const std::string why = graph::parseBlockRecord(rec, blobs_, r);  // checked at open, unless paged over a link
  if (!why.empty())
    throw core::Error(core::Status::Corrupt, name_ + ": block section BLCK at offset " +
                                                 std::to_string(records_offset_ + uint64_t(b) * shape_.record_size) +
                                                 ": block " + std::to_string(b) + ": " + why);
  return r;
}

}  // namespace blvd::stream
