// The table page CRCs (section TPCR, from package 3.2): a CRC32C for every
// page of every table section, so that a reader fetching a table a page at a
// time over the network checks each page alone, as strictly as a section
// checked whole. docs/package-format.md has the layout:
//   u32 version (1), u32 page_bytes, u32 count,
//   count × {u32 tag, u32 pages}, then every listed section's page CRCs in
//   that order (page k of a section: its bytes [k × page_bytes, (k+1) ×
//   page_bytes), the last one shorter).
// The writer lists every section it was given (not BIDX, BDAT or TPCR).
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"
#include "package/format.h"

namespace blvd::package {

inline constexpr uint32_t kTablePagesVersion = 1;
inline constexpr uint32_t kTablePageBytes = 4096;

// Where one section's page CRCs are.
struct TablePageRun {
  uint32_t tag = 0;
  uint64_t section_offset = 0, section_size = 0;  // the section's place in the file
  uint32_t pages = 0;
  uint64_t crcs_at = 0;  // byte offset of its first CRC inside TPCR
};

struct TablePages {
  uint32_t page_bytes = kTablePageBytes;
  std::vector<TablePageRun> runs;
  // The run of the section holding file offset `at`, or null.
  const TablePageRun* find(uint64_t at) const;
};

// TPCR's bytes for `sections` (tag and bytes), pages of kTablePageBytes.
std::vector<uint8_t> encodeTablePages(const std::vector<std::pair<uint32_t, const std::vector<uint8_t>*>>& sections);

// Parses TPCR (its bytes, at file offset `offset`) against the directory:
// every run names a section of the directory other than BIDX, BDAT and TPCR,
// once, with as many pages as its size needs, and the CRCs fill the section
// exactly. Corrupt naming `name` and the offset otherwise.
core::Status parseTablePages(const uint8_t* data, size_t size, uint64_t offset,
                             const std::vector<SectionInfo>& sections, const std::string& name, TablePages& out,
                             std::string& err);

// Page k of a run's CRC, read from TPCR's bytes.
uint32_t tablePageCrc(const uint8_t* tpcr, const TablePageRun& run, uint32_t k);

}  // namespace blvd::package
