// RemotePackage: a package read over HTTP(S) range requests (PMTiles is the
// model), its tables mirrored on disk and its blobs kept in a DiskCache.
//
// open() costs one request when the first 16 KiB hold the header and the
// directory (every package the bake writes: a handful of sections); it checks
// them with the same parsers as the mmap reader (package/format.h). With a
// cache folder, one more request (in pieces of 4 MiB) copies every table
// section into the table mirror (table_mirror.h) unless the mirror there is
// already this package's, and the blob index is read from it; without one,
// the blob index is fetched alone. The package's identity is the CRC32C of
// its header and directory bytes with its size: the directory holds every
// section's CRC, BIDX's among them, which holds every blob's, so two packages
// with one byte different differ in identity; the cache is keyed by it. Every
// section and blob is CRC-checked before it is returned or cached.
//
// A package with table page CRCs (TPCR, package 3.2) is mirrored lazily:
// open copies only its TPCR and blob index, and ensureTables() fetches the
// table pages a reader is about to read, each checked against its CRC before
// it is written into the mirror and each time it is found there. A cold start
// then costs what the first cell reads, not every table.
//
// Offline (LinkMode::Offline, or a link that fails at open while a mirror is
// there) the package opens from the mirror and serves cached blobs only: a
// blob that is not cached is Status::Unavailable, never a wait.
//
// Threading: any thread. The cache and the link have a lock each, so a
// cached blob is served while another thread waits on the link.
#pragma once
#include <atomic>
#include <chrono>
#include <functional>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/status.h"
#include "package/format.h"
#include "package/table_pages.h"
#include "remote/disk_cache.h"
#include "remote/range_client.h"

namespace blvd::remote {

using package::BlobInfo;
using package::HeaderLayout;
using package::PackageHeader;
using package::SectionInfo;

// online: fetch what is asked for; metered: the same, the caller asks only
// for the current and next cells; offline: cached blobs only.
enum class LinkMode : uint32_t { Online = 0, Metered = 1, Offline = 2 };

struct RemoteOptions {
  LinkOptions link;
  std::string cache_path;    // empty: no table mirror, no disk cache
  uint64_t cache_bytes = 0;  // mirror and blobs together
  LinkMode mode = LinkMode::Online;
};

struct RemoteStats {
  LinkStats link;
  CacheStats cache;
  uint64_t cache_bytes = 0;    // on disk now: mirror and blobs
  uint64_t mirror_bytes = 0;   // of which the table mirror
  uint64_t cache_bytes_max = 0;  // what the blob cache may hold (cache_bytes less the mirror)
  double throughput_bps = 0;   // bytes per second of recent fetches (0 until one)
  uint64_t table_bytes = 0;    // of link.bytes, the tables' (open, table pages)
  bool changed = false;        // the package on the server is not this one any more
  bool offline_start = false;  // opened from the mirror: the link failed or the mode is offline
};

class RemotePackage {
 public:
  RemotePackage() = default;
  ~RemotePackage();
  RemotePackage(const RemotePackage&) = delete;
  RemotePackage& operator=(const RemotePackage&) = delete;

  // Io/NotFound when the link or the server fails, Corrupt when what arrives
  // is not a package (err names the URL and the offset), Unsupported for
  // another major version.
  // A cache_bytes that cannot hold the mirror and the largest blob is
  // InvalidArg; an offline open without a mirror is Unavailable.
  core::Status open(const std::string& url, const RemoteOptions& opt, std::string& err);
  // The table mirror's path ("" without a cache folder).
  const std::string& mirrorPath() const { return mirror_; }
  const std::string& url() const { return url_; }

  const std::string& identity() const { return identity_; }
  const PackageHeader& header() const { return layout_.header; }
  uint64_t fileSize() const { return layout_.file_size; }
  const std::vector<SectionInfo>& sections() const { return sections_; }
  uint32_t blobCount() const { return uint32_t(blobs_.size()); }
  const BlobInfo& blobInfo(uint32_t i) const { return blobs_[i]; }

  // Whether the mirror fills a table page at a time (ensureTables).
  bool lazyTables() const { return mirror_fd_ >= 0; }
  // Makes the mirror hold file bytes [offset, offset + size) of a table
  // section: each table page they touch is read from the mirror and checked
  // against its CRC; those missing or wrong are fetched (neighbours in one
  // request, foreground on the link), checked and written. Unavailable
  // offline when one is missing; Corrupt when the server's fails its CRC; the
  // link's status otherwise. Ok at once for an eager mirror or bytes outside
  // every table section.
  // Without `wait` (the render thread: a frame never waits for the link) a
  // missing page is not fetched here but asked for (tablesWanted(); the link
  // prefetch's thread fetches it) and the call is Unavailable at once.
  core::Status ensureTables(uint64_t offset, uint64_t size, std::string& err, bool wait = true);
  // The oldest range a caller that would not wait asked for, if any.
  bool takeWantedTables(uint64_t* offset, uint64_t* size);
  bool tablesWanted() const;
  void clearWantedTables();  // the link failed: a frame asks again
  // Whether a request failed for the link (not the server) in the last
  // kLinkDownS: a frame's missing table page is then not even asked for.
  bool linkDown() const;
  static constexpr std::chrono::seconds kLinkDownS{2};
  // Called (on the asking thread) when a range is asked for.
  void onTablesWanted(std::function<void()> f) { on_wanted_ = std::move(f); }
  // Fetches every table page the mirror lacks, background priority on the
  // link, a few pages a request, until done or stop() says so (checked
  // between requests): a car that has the first frame completes its map
  // for when the link goes. The link's status.
  core::Status fillTables(std::string& err, const std::function<bool()>& stop);
  // Whether fillTables() found every table page there (an eager mirror always).
  bool tablesComplete() const { return mirror_fd_ < 0 || tables_complete_.load(std::memory_order_relaxed); }

  // A section's bytes, CRC-checked (NotFound when the package has none).
  core::Status section(uint32_t tag, std::vector<uint8_t>& out, std::string& err);
  // Blob i's bytes: from the cache when there and whole, else fetched,
  // checked and cached (Unavailable offline). `from_cache` (optional) says
  // which.
  core::Status blob(uint32_t i, std::vector<uint8_t>& out, std::string& err, bool* from_cache = nullptr);
  // Fetches the blobs of ids[0 .. n) that are not cached into the cache,
  // neighbours in the file (gaps under 4 KiB, at most 4 MiB) in one request.
  // Unavailable offline when one is missing; the link's status otherwise.
  // `background` (the link prefetch): each request waits while a
  // foreground one (a cell's load) wants the link.
  core::Status fetchBlobs(const uint32_t* ids, size_t n, std::string& err, bool background = false);
  // Asks the server whether the package is still this one (16 bytes with
  // If-Match): a car that has all it needs cached still notices a new
  // version. Background priority; the link's status.
  core::Status revalidate(std::string& err);
  // Whether blob i is in the cache now.
  bool cached(uint32_t i) const;
  // Blobs the cache must keep (the current and predicted cells').
  void pin(const std::vector<uint32_t>& blobs);
  void setMode(LinkMode m) { mode_.store(m, std::memory_order_relaxed); }
  LinkMode mode() const { return mode_.load(std::memory_order_relaxed); }

  // Whether the package on the server changed since open (an ETag that no
  // longer matches): reopen to get the new one; nothing of the old is mixed in.
  bool changed() const { return changed_.load(std::memory_order_relaxed); }
  // Never waits for the link (a snapshot taken after each request).
  RemoteStats stats() const;
  // Bytes per second of recent fetches (0 until one); never waits for the cache either.
  double throughput() const;

  static constexpr uint64_t kFirstRead = 16384;

 private:
  core::Status fetchChecked(uint64_t offset, uint64_t size, uint32_t crc, const std::string& what,
                            std::vector<uint8_t>& out, std::string& err);
  core::Status readHead(const RemoteOptions& opt, std::vector<uint8_t>& head, uint64_t& file_size, std::string& err);
  core::Status openTables(const std::vector<uint8_t>& head, std::string& err);
  core::Status openTablePages(const SectionInfo& tpcr, std::string& err);  // TPCR from the mirror; its descriptor
  bool pagePresent(const package::TablePageRun& run, uint32_t k) const;  // in the mirror and whole
  bool tablesPresent(uint64_t offset, uint64_t size) const;
  core::Status askForTables(uint64_t offset, uint64_t size, std::string& err);  // Unavailable
  core::Status fetchTablePages(const package::TablePageRun& run, uint32_t k0, uint32_t k1, std::string& err,
                               bool background = false);
  core::Status openCache(const RemoteOptions& opt, std::string& err);
  core::Status fetchRun(const uint32_t* run, size_t n, std::string& err, bool background);  // ids by offset
  // Runs f (a request) holding the link; a foreground caller goes before
  // waiting background ones. Updates the stats snapshot after.
  template <typename F>
  core::Status onLink(bool background, uint64_t bytes, F&& f);

  std::string url_, identity_, mirror_;
  std::unique_ptr<RangeClient> client_;
  std::unique_ptr<DiskCache> cache_;
  HeaderLayout layout_;
  std::vector<SectionInfo> sections_;
  std::vector<BlobInfo> blobs_;
  std::atomic<LinkMode> mode_{LinkMode::Online};
  uint64_t mirror_bytes_ = 0;
  package::TablePages table_pages_;
  std::vector<uint8_t> tpcr_;  // TPCR's bytes (4 per table page)
  int mirror_fd_ = -1;         // the mirror, read and written a page at a time when lazy
  std::mutex table_mu_;        // one foreground ensureTables() at a time (taken before link_mu_)
  std::atomic<bool> tables_complete_{false};
  mutable std::mutex wanted_mu_;  // the ranges below
  std::pair<uint64_t, uint64_t> wanted_[16];
  size_t wanted_n_ = 0;
  std::function<void()> on_wanted_;
  std::atomic<int64_t> link_down_until_{0};  // steady_clock ticks
  void markLinkDown();
  static constexpr uint32_t kFillPages = 4;  // 16 KiB a request: 2.3 s of a 56 kbit/s link in front of a frame's page
  std::atomic<uint64_t> table_bytes_{0};
  bool offline_start_ = false;
  mutable std::mutex cache_mu_, link_mu_;  // cache_ and client_; when both, cache_mu_ first
  mutable std::mutex stats_mu_;            // the snapshot below
  LinkStats link_stats_;
  double throughput_bps_ = 0;
  std::atomic<bool> changed_{false};
  std::atomic<int> foreground_{0};
};

}  // namespace blvd::remote
