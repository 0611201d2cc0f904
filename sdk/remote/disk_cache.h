// DiskCache: a package's blobs kept on disk, in at most max_bytes, for a car
// that fetches them over the air (range_client.h).
//
// - Keyed by the package's identity (package_identity.h), not by URL and
//   range, so blobs of two versions of a package are never mixed: opening the
//   cache for another identity removes the other's entries.
// - Never more than max_bytes on disk (entry files, headers included): a put
//   evicts least-recently-used entries first, never pinned ones (the current
//   and predicted cells'); what cannot fit is not cached (the caller keeps
//   its bytes: nothing is lost).
// - Every entry carries the blob's CRC32C (the package's BIDX value) and is
//   checked on put and on every get; a bad, truncated or foreign entry is
//   dropped, never returned. Entries are written to a temporary name and
//   renamed, so a killed process leaves whole entries or none; a full disk
//   fails the put, nothing else.
// - Survives restarts: open() scans the folder, checks each entry's header
//   and size, and orders them by their last use (file mtime).
//
// Threading: one thread at a time.
#pragma once
#include <cstdint>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "core/status.h"

namespace blvd::remote {

struct CacheStats {
  uint64_t hits = 0, misses = 0, puts = 0, evictions = 0;
  uint64_t dropped = 0;       // entries found bad (header, size or CRC) and removed
  uint64_t not_cached = 0;    // puts that did not fit or that the disk refused
};

class DiskCache {
 public:
  // Opens `dir` (created if missing) for the package `identity` (a hex
  // string). Io when the folder cannot be made or read, InvalidArg for an
  // empty identity or a max_bytes smaller than one entry header.
  core::Status open(const std::string& dir, uint64_t max_bytes, const std::string& identity, std::string& err);

  // The blob's bytes, when cached and whole (CRC32C == crc); a bad entry is
  // dropped and counted.
  bool get(uint32_t blob, uint32_t crc, std::vector<uint8_t>& out);
  // Caches the blob when its CRC32C is `crc` and it fits (evicting unpinned
  // entries, least recently used first). False when not cached.
  bool put(uint32_t blob, uint32_t crc, const uint8_t* data, size_t size);
  // The blobs that must stay (replaces the previous set).
  void pin(const std::vector<uint32_t>& blobs);

  bool contains(uint32_t blob) const { return entries_.count(blob) != 0; }
  uint64_t bytes() const { return bytes_; }          // on disk, headers included
  uint64_t maxBytes() const { return max_bytes_; }
  size_t entries() const { return entries_.size(); }
  const CacheStats& stats() const { return stats_; }

  static constexpr uint64_t kHeaderBytes = 24;  // magic, blob, crc, size

 private:
  struct Entry {
    uint64_t bytes = 0;  // file size
    uint64_t used = 0;   // last use, for LRU (higher is more recent)
  };
  std::string pathOf(uint32_t blob) const;
  void drop(uint32_t blob, bool bad);
  bool makeRoom(uint64_t need);
  void touch(uint32_t blob);

  std::string dir_;  // dir/identity
  uint64_t max_bytes_ = 0, bytes_ = 0, clock_ = 0;
  uint64_t stamp_ = 0;  // the latest use written to an entry's mtime, ns
  std::unordered_map<uint32_t, Entry> entries_;
  std::unordered_set<uint32_t> pinned_;
  CacheStats stats_;
};

}  // namespace blvd::remote
