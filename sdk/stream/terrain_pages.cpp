#include "stream/terrain_pages.h"

#include <algorithm>
#include <vector>

namespace blvd::stream {

core::Status TerrainPages::open(const package::PackageReader& reader, std::string& err, const PageSource* source) {
  *this = TerrainPages{};
  package::Span s;
  core::Status st = tableSection(reader, source, package::kSectionTerrain, s, err);
  if (st != core::Status::Ok) return st;
  name_ = reader.name();
  blobs_ = reader.blobCount();
  std::vector<uint8_t> head;  // read, never touched through the mapping
  try {
    if (source) source->ensure(s.offset, std::min<uint64_t>(s.size, graph::kTerrainHeaderBytes));
    if ((st = reader.copy(s, head, err, graph::kTerrainHeaderBytes)) != core::Status::Ok) return st;
    layout_ = graph::parseTerrainHeader(head.data(), s.size, s.offset);  // reads the header only
  } catch (const core::Error& e) {
    err = name_ + ": " + e.what();
    return e.status();
  }
  records_offset_ = s.offset + graph::kTerrainHeaderBytes;
  cache_ = std::make_unique<PageCache>(reader, kPages, kPageBytes, source);
  table_ = cache_->addTable(s.data + graph::kTerrainHeaderBytes, layout_.tiles(), graph::kTerrainRecordBytes);
  if (source) return core::Status::Ok;
  graph::TerrainRecord r;
  try {
    for (uint32_t i = 0; i < layout_.tiles(); ++i)
      if (err = check(i, r); !err.empty()) return core::Status::Corrupt;
  } catch (const core::Error& e) {  // a read that failed
    err = e.what();
    return e.status();
  }
  return core::Status::Ok;
}

std::string TerrainPages::check(uint32_t i, graph::TerrainRecord& r) const {
  uint8_t rec[graph::kTerrainRecordBytes];
  cache_->read(table_, i, rec);
  const std::string why = graph::parseTerrainRecord(rec, blobs_, r);
  if (why.empty()) return why;
  return name_ + ": terrain section TERR at offset " +
         std::to_string(records_offset_ + uint64_t(i) * graph::kTerrainRecordBytes) + ": tile " + std::to_string(i) +
         ": " + why;
}

graph::TerrainRecord TerrainPages::record(uint32_t i) const {
  graph::TerrainRecord r;
  if (std::string why = check(i, r); !why.empty()) throw core::Error(core::Status::Corrupt, why);
  return r;
}

}  // namespace blvd::stream
