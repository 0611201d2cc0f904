// PackageWriter: collects the header, sections and blobs of one package and
// writes the file in one go (the format is immutable: no append, no update).
//
// Threading: one thread at a time. Memory: holds every section and blob until
// write(); a package is bounded by what the bake produced anyway.
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "package/blob_codec.h"
#include "package/format.h"

namespace blvd::package {

class PackageWriter {
 public:
  // Copied as is, except version_major/minor: the writer always records the
  // format version it writes (kVersionMajor.kVersionMinor).
  void setHeader(const PackageHeader& header);
  const PackageHeader& header() const { return header_; }

  // Adds a section. Throws core::Error(InvalidArg) when `tag` was added before
  // or is TPCR/BIDX/BDAT (the writer owns those: TPCR, a CRC per page of every
  // section added, goes after them). Sections are laid out in the order
  // they are added, so put the small ones a remote client wants first.
  void addSection(uint32_t tag, std::vector<uint8_t> bytes);

  // Adds a blob (a block or cell GLB, a terrain tile) and returns its index,
  // 0, 1, 2 ... in call order. The index is what the BLCK/CELL sections
  // store. Stored as packBlob(contents, level) with the level of
  // setBlobCompression().
  uint32_t addBlob(std::vector<uint8_t> contents);
  // Adds a blob packed already (packBlob() on a worker thread, or a blob
  // copied from another package's BDAT with its BIDX flags).
  uint32_t addStoredBlob(StoredBlob blob);
  // The zstd level addBlob() stores blobs at; 0 (the default) stores them as
  // they are. Throws as packBlob() for a level outside 0..22.
  void setBlobCompression(int level);
  uint32_t blobCount() const { return static_cast<uint32_t>(blobs_.size()); }
  // The stored bytes of blob `i` (< blobCount()), what BIDX's size counts.
  // The reference is valid until the next addBlob().
  const std::vector<uint8_t>& blob(uint32_t i) const { return blobs_.at(i).bytes; }
  // Blob `i`'s contents, decompressed when it is stored compressed.
  std::vector<uint8_t> blobContents(uint32_t i) const;

  // Bytes the section will occupy without padding; for BIDX and BDAT the size
  // (and TPCR) the writer will give them; 0 for a tag that was not added.
  uint64_t sectionBytes(uint32_t tag) const;
  // Size of the file write() produces.
  uint64_t fileBytes() const;

  // Writes `path + ".tmp"`, fsyncs it and renames it over `path`, so a crash
  // leaves either the old file or the whole new one. Throws core::Error(Io)
  // naming the path and the errno text; the .tmp file is removed on failure.
  void write(const std::string& path) const;

  // The same bytes write() puts in the file (for tests, fuzz seeds and
  // PackageReader::openMemory).
  std::vector<uint8_t> toBytes() const;

 private:
  struct Section {
    uint32_t tag;
    uint32_t crc;
    std::vector<uint8_t> bytes;
  };
  struct Blob {
    uint32_t crc;
    uint64_t rel_offset;  // from the start of BDAT (which is 8-aligned in the file)
    std::vector<uint8_t> bytes;
    uint32_t flags;
    uint64_t contents_size;
  };
  struct Layout;
  Layout layout() const;
  std::vector<uint8_t> tablePages() const;  // TPCR over the sections given
  template <typename Sink>
  void emit(Sink&& sink) const;

  PackageHeader header_;
  std::vector<Section> sections_;
  std::vector<Blob> blobs_;
  // BDAT grows blob by blob, so its size and CRC are kept running instead of
  // being recomputed over every blob at write time.
  uint64_t bdat_size_ = 0;
  uint32_t bdat_crc_ = 0;
  int blob_level_ = 0;
};

}  // namespace blvd::package
