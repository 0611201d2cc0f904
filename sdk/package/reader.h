// PackageReader: the runtime's view of one package file, memory-mapped
// read-only and validated once at open.
//
// Open checks magic, header CRC, version, the directory (CRC, every section
// inside the file, aligned, not overlapping) and every blob's offset/length,
// but not the CRC of every section and blob: that would touch the whole file
// before the first frame. blob() checks the CRC of the blob it returns and
// checkedSection() of the section; verify() checks everything.
//
// Errors never throw (except openOrThrow): a truncated, corrupt or foreign file
// gives Status::Corrupt (Unsupported for another major version, Io when the
// file cannot be opened) and a message "<path>: <what> at offset <n>: <why>".
//
// Threading: after open, every const method may be called from any number of
// threads at once (the object is immutable). Lifetime: Spans point into the
// mapping and stay valid until the reader is closed, destroyed or moved from.
//
// A file truncated while open: open() itself reads the header, directory and
// indexes with pread (read()), and so do checkedSection() and copy(). A reader
// opened with Access::Read (the runtime) maps nothing: its Spans only name
// places (offsetOf), their bytes come through read(), readBlob() and copy(),
// so a file cut short under it, even while it is being opened, gives
// Status::Io naming the offset, never a SIGBUS from a page past the file's new
// end. Access::Map (tools that hold the file: pack verify, merge) maps it for
// blob(), section() bytes and verify(). (A package is meant to be replaced by
// renaming a new file over it, which keeps the open one intact.)
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"
#include "package/format.h"
#include "package/table_pages.h"

namespace blvd::package {

// A range of the package: `data` points into the mapping (with Access::Read,
// into an address range that only names it: read its bytes with copy()),
// `offset` is where it starts in the file (for messages and range requests).
struct Span {
  const uint8_t* data = nullptr;
  size_t size = 0;
  uint64_t offset = 0;
  bool empty() const { return size == 0; }
};

class PackageReader {
 public:
  PackageReader() = default;
  ~PackageReader();
  PackageReader(PackageReader&& o) noexcept;
  PackageReader& operator=(PackageReader&& o) noexcept;
  PackageReader(const PackageReader&) = delete;
  PackageReader& operator=(const PackageReader&) = delete;

  enum class Access { Map, Read };
  // Opens `path` and validates it: mapped (PROT_READ, MAP_PRIVATE) with
  // Access::Map; with Access::Read only an address range of the file's size
  // is reserved (PROT_NONE: a byte touched there is a bug, not a read) and
  // every byte is read with pread. On success `out` holds the package
  // (whatever it held before is closed); on failure `out` is left closed and
  // `err` says what is wrong.
  static core::Status open(const std::string& path, PackageReader& out, std::string& err,
                           Access access = Access::Map);
  // The same, throwing core::Error(status, err) instead.
  static PackageReader openOrThrow(const std::string& path);
  // Validates a package that is already in memory (embedded in the host, or
  // fetched). Does not copy: `data` must outlive the reader. `name` is used in
  // messages in place of a path.
  static core::Status openMemory(const uint8_t* data, size_t size, const std::string& name,
                                 PackageReader& out, std::string& err);

  bool isOpen() const { return data_ != nullptr; }
  void close();

  const std::string& name() const { return name_; }  // the path given to open()
  const PackageHeader& header() const { return layout_.header; }
  uint64_t fileSize() const { return size_; }
  // The file offset of `p`, a pointer into the mapping.
  uint64_t offsetOf(const uint8_t* p) const { return static_cast<uint64_t>(p - data_); }
  // Directory order, BIDX and BDAT included (for `blvd pack info`).
  const std::vector<SectionInfo>& sections() const { return sections_; }

  bool hasSection(uint32_t tag) const;
  // The section's bytes without a CRC check, or an empty Span (data null)
  // when the package has no such section: absent optional sections are
  // normal, so this does not throw. Use hasSection() to tell absent from empty.
  Span section(uint32_t tag) const;
  // The section after checking its CRC (read in pieces, not through the
  // mapping): NotFound when absent, Corrupt (naming section and offset) when
  // the CRC does not match, Io when the file no longer holds it.
  core::Status checkedSection(uint32_t tag, Span& out, std::string& err) const;
  // The first `limit` bytes of `s` (all of them by default) read into `out`
  // (resized to what was read): what a parser reads, whatever the access.
  core::Status copy(const Span& s, std::vector<uint8_t>& out, std::string& err, size_t limit = SIZE_MAX) const;
  // The section read whole into `out` and its CRC checked there; `where`
  // points at the copy. Errors as checkedSection().
  core::Status checkedCopy(uint32_t tag, std::vector<uint8_t>& out, Span& where, std::string& err) const;

  // The table page CRCs (TPCR, package 3.2), parsed at open; null in an older
  // package. tablePageCrc() reads them from section(kSectionTablePages).
  const TablePages* tablePages() const { return has_table_pages_ ? &table_pages_ : nullptr; }

  uint32_t blobCount() const { return static_cast<uint32_t>(blobs_.size()); }
  // Offset, size and CRC of blob `i` without reading it (for range clients and
  // stats). `i` must be < blobCount().
  const BlobInfo& blobInfo(uint32_t i) const { return blobs_[i]; }
  // Blob `i`, zero-copy, after checking its CRC. NotFound for i >= blobCount(),
  // Corrupt naming the blob and its offset when the CRC does not match.
  // Touches the mapping: for tools that hold the file (pack verify, merge);
  // Misuse with Access::Read.
  core::Status blob(uint32_t i, Span& out, std::string& err) const;
  // Blob `i` copied into `into` (grown when too small, never shrunk), then its
  // CRC checked; `out` points into `into`. As blob(), plus Io when the file no
  // longer holds it (truncated since open). What the runtime uses.
  core::Status readBlob(uint32_t i, std::vector<uint8_t>& into, Span& out, std::string& err) const;
  // Blob `i`'s contents (a GLB, a terrain tile), decompressed when BIDX says
  // it is stored as a zstd frame (blob_codec.h); errors as blob() and
  // readBlob(), plus Corrupt for a damaged frame. blobContents() reads through
  // the mapping (tools; `out` may point into it), readBlobContents() with
  // pread (the runtime; `out` points into `into`, which is grown when too
  // small and never shrunk).
  core::Status blobContents(uint32_t i, std::vector<uint8_t>& into, Span& out, std::string& err) const;
  core::Status readBlobContents(uint32_t i, std::vector<uint8_t>& into, Span& out, std::string& err) const;
  // `size` bytes at file offset `offset` into `dst`: pread from the file (a
  // package read into memory: a copy). Io naming the offset and the file's
  // size now when it holds fewer (truncated since open); Misuse past the end
  // the reader opened.
  core::Status read(uint64_t offset, size_t size, uint8_t* dst, std::string& err) const;

  // Checks every checksum (header, directory, each section, each blob) and that
  // the padding between sections is zero; names the first bad one and its
  // offset. Reads the whole file through the mapping (Misuse with Access::Read).
  core::Status verify(std::string& err) const;


 private:
  core::Status validate(std::string& err);
  core::Status verifyTablePages(std::string& err) const;
  core::Status blobExists(uint32_t i, std::string& err) const;
  core::Status checkBlob(uint32_t i, const uint8_t* bytes, Span& out, std::string& err) const;
  core::Status mapped(std::string& err) const;
  const SectionInfo* find(uint32_t tag) const;
  core::Status readHeader(std::vector<uint8_t>& bytes, std::string& err) const;

  const uint8_t* data_ = nullptr;
  size_t size_ = 0;
  bool mapped_ = false;    // we own the mapping (open) rather than borrow (openMemory)
  bool reserved_ = false;  // Access::Read: data_ is a PROT_NONE range, not the file
  int fd_ = -1;          // kept open for read(): the file, when mapped_
  std::string name_;
  HeaderLayout layout_;
  std::vector<SectionInfo> sections_;
  std::vector<BlobInfo> blobs_;
  TablePages table_pages_;
  bool has_table_pages_ = false;
};

}  // namespace blvd::package
