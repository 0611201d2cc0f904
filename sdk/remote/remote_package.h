// RemotePackage: a package read over HTTP(S) range requests (PMTiles is the
// model), its blobs kept in a DiskCache.
//
// open() costs one request when the first 16 KiB hold the header and the
// directory (every package the bake writes: a handful of sections), plus one
// for the blob index; it checks them with the same parsers as the mmap reader
// (package/format.h). The package's identity is the CRC32C of its header and
// directory bytes with its size: the directory holds every section's CRC,
// BIDX's among them, which holds every blob's, so two packages with one byte
// different differ in identity; the cache is keyed by it. Every section and
// blob is CRC-checked before it is returned or cached.
//
// Threading: one thread at a time (a loader's). Memory: the blob index and
// what the caller asks for.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/status.h"
#include "package/format.h"
#include "remote/disk_cache.h"
#include "remote/range_client.h"

namespace blvd::remote {

using package::BlobInfo;
using package::HeaderLayout;
using package::PackageHeader;
using package::SectionInfo;

struct RemoteOptions {
  LinkOptions link;
  std::string cache_path;    // empty: no disk cache
  uint64_t cache_bytes = 0;
};

class RemotePackage {
 public:
  // Io/NotFound when the link or the server fails, Corrupt when what arrives
  // is not a package (err names the URL and the offset), Unsupported for
  // another major version.
  core::Status open(const std::string& url, const RemoteOptions& opt, std::string& err);

  const std::string& identity() const { return identity_; }
  const PackageHeader& header() const { return layout_.header; }
  uint64_t fileSize() const { return layout_.file_size; }
  const std::vector<SectionInfo>& sections() const { return sections_; }
  uint32_t blobCount() const { return uint32_t(blobs_.size()); }
  const BlobInfo& blobInfo(uint32_t i) const { return blobs_[i]; }

  // A section's bytes, CRC-checked (NotFound when the package has none).
  core::Status section(uint32_t tag, std::vector<uint8_t>& out, std::string& err);
  // Blob i's bytes: from the cache when there and whole, else fetched,
  // checked and cached. `from_cache` (optional) says which.
  core::Status blob(uint32_t i, std::vector<uint8_t>& out, std::string& err, bool* from_cache = nullptr);
  // Blobs the cache must keep (the current and predicted cells').
  void pin(const std::vector<uint32_t>& blobs);

  // Whether the package on the server changed since open (an ETag that no
  // longer matches): reopen to get the new one; nothing of the old is mixed in.
  bool changed() const { return client_ && client_->changed(); }
  const LinkStats& linkStats() const { return client_->stats(); }
  const DiskCache* cache() const { return cache_ ? cache_.get() : nullptr; }

  static constexpr uint64_t kFirstRead = 16384;

 private:
  core::Status fetchChecked(uint64_t offset, uint64_t size, uint32_t crc, const std::string& what,
                            std::vector<uint8_t>& out, std::string& err);

  std::string url_, identity_;
  std::unique_ptr<RangeClient> client_;
  std::unique_ptr<DiskCache> cache_;
  HeaderLayout layout_;
  std::vector<SectionInfo> sections_;
  std::vector<BlobInfo> blobs_;
};

}  // namespace blvd::remote
