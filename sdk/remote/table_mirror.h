// TableMirror: a package's tables on local disk, so that the mmap reader, the
// paged tables and the tracker read a package on a server as they read a
// local one.
//
// The mirror is a file of the package's size (package/format.h) holding the
// header, the directory and every section but the blob data (BDAT), which is
// left a hole (a sparse file: it takes no disk). Blobs come one cell at a
// time through the disk cache instead (disk_cache.h). The mirror is written
// to a temporary name and renamed, so a killed process leaves the old mirror
// or the new one; its sections' CRCs are checked by whoever opens it
// (stream::City checks every table section it reads).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"
#include "package/format.h"
#include "remote/range_client.h"

namespace blvd::remote {

// The byte ranges the mirror needs besides `head` (the first bytes, already
// fetched): every section but BDAT, adjacent ones merged, as [begin, end).
std::vector<std::pair<uint64_t, uint64_t>> mirrorRanges(const std::vector<package::SectionInfo>& sections,
                                                        uint64_t head);

// Bytes the mirror holds on disk: `head` plus the ranges.
uint64_t mirrorBytes(const std::vector<package::SectionInfo>& sections, uint64_t head);

// Writes the mirror at `path`: `head` at offset 0, then each range of
// `sections` (mirrorRanges) fetched through `client` in pieces of at most
// 4 MiB. A package with table page CRCs gets only its TPCR and BIDX here; its
// other tables arrive a page at a time (RemotePackage::ensureTables). Io when the disk refuses (a
// full disk: the temporary is removed), or the link's status.
core::Status writeMirror(RangeClient& client, const std::string& path, uint64_t file_size,
                         const std::vector<uint8_t>& head, const std::vector<package::SectionInfo>& sections,
                         std::string& err);

// The first `n` bytes of the mirror at `path` (fewer when it is shorter)
// and its size; false when there is no mirror.
bool readMirrorHead(const std::string& path, size_t n, std::vector<uint8_t>& out, uint64_t& file_size);

// Bytes [offset, offset + size) of the mirror; false when it is short.
// The *At forms use an open descriptor.
bool readMirrorAt(int fd, uint64_t offset, uint64_t size, uint8_t* out);
bool writeMirrorAt(int fd, uint64_t offset, const uint8_t* p, uint64_t size);
bool readMirror(const std::string& path, uint64_t offset, uint64_t size, std::vector<uint8_t>& out);

}  // namespace blvd::remote
