// Table page CRCs; the contract is in table_pages.h.
#include "package/table_pages.h"

#include <algorithm>
#include <cstring>

namespace blvd::package {
namespace {

constexpr size_t kHead = 12, kRun = 8;

uint32_t get32(const uint8_t* p) {
  uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}

void put32(std::vector<uint8_t>& out, uint32_t v) {
  const size_t at = out.size();
  out.resize(at + 4);
  std::memcpy(out.data() + at, &v, 4);
}

uint32_t pagesOf(uint64_t size, uint32_t page) { return static_cast<uint32_t>((size + page - 1) / page); }

}  // namespace

const TablePageRun* TablePages::find(uint64_t at) const {
  for (const TablePageRun& r : runs)
    if (at >= r.section_offset && at < r.section_offset + r.section_size) return &r;
  return nullptr;
}

std::vector<uint8_t> encodeTablePages(const std::vector<std::pair<uint32_t, const std::vector<uint8_t>*>>& sections) {
  std::vector<uint8_t> out;
  put32(out, kTablePagesVersion);
  put32(out, kTablePageBytes);
  put32(out, static_cast<uint32_t>(sections.size()));
  for (const auto& [tag, bytes] : sections) {
    put32(out, tag);
    put32(out, pagesOf(bytes->size(), kTablePageBytes));
  }
  for (const auto& [tag, bytes] : sections)
    for (size_t at = 0; at < bytes->size(); at += kTablePageBytes)
      put32(out, crc32c(bytes->data() + at, std::min<size_t>(kTablePageBytes, bytes->size() - at)));
  return out;
}

core::Status parseTablePages(const uint8_t* data, size_t size, uint64_t offset,
                             const std::vector<SectionInfo>& sections, const std::string& name, TablePages& out,
                             std::string& err) {
  out = TablePages{};
  auto bad = [&](uint64_t at, const std::string& why) {
    err = name + ": table page CRCs TPCR at offset " + std::to_string(offset + at) + ": " + why;
    return core::Status::Corrupt;
  };
  if (size < kHead) return bad(0, "truncated");
  if (get32(data) != kTablePagesVersion) return bad(0, "unknown version " + std::to_string(get32(data)));
  out.page_bytes = get32(data + 4);
  if (out.page_bytes < 512 || out.page_bytes > (1u << 24) || (out.page_bytes & (out.page_bytes - 1)))
    return bad(4, "page size " + std::to_string(out.page_bytes) + " is not a power of two in [512, 16 MiB]");
  const uint32_t count = get32(data + 8);
  if (count > sections.size() || kHead + uint64_t(count) * kRun > size) return bad(8, "more runs than the directory has sections");
  uint64_t crcs_at = kHead + uint64_t(count) * kRun;
  for (uint32_t i = 0; i < count; ++i) {
    const uint8_t* e = data + kHead + size_t(i) * kRun;
    TablePageRun r;
    r.tag = get32(e);
    r.pages = get32(e + 4);
    const SectionInfo* s = nullptr;
    for (const SectionInfo& si : sections)
      if (si.tag == r.tag) s = &si;
    const uint64_t at = kHead + uint64_t(i) * kRun;
    if (!s || r.tag == kSectionBlobIndex || r.tag == kSectionBlobData || r.tag == kSectionTablePages)
      return bad(at, "run " + std::to_string(i) + " names " + tagToString(r.tag) + ", not a table section");
    for (const TablePageRun& o : out.runs)
      if (o.tag == r.tag) return bad(at, "section " + tagToString(r.tag) + " listed twice");
    if (r.pages != pagesOf(s->size, out.page_bytes))
      return bad(at + 4, "section " + tagToString(r.tag) + " of " + std::to_string(s->size) + " bytes has " +
                             std::to_string(pagesOf(s->size, out.page_bytes)) + " pages, not " + std::to_string(r.pages));
    r.section_offset = s->offset;
    r.section_size = s->size;
    r.crcs_at = crcs_at;
    crcs_at += uint64_t(r.pages) * 4;
    out.runs.push_back(r);
  }
  if (crcs_at != size)
    return bad(0, "section is " + std::to_string(size) + " bytes, its runs say " + std::to_string(crcs_at));
  return core::Status::Ok;
}

uint32_t tablePageCrc(const uint8_t* tpcr, const TablePageRun& run, uint32_t k) {
  return get32(tpcr + run.crcs_at + uint64_t(k) * 4);
}

}  // namespace blvd::package
