// A package over range requests; the contract is in remote_package.h.
#include "remote/remote_package.h"

#include <algorithm>
#include <chrono>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <thread>

#include <fcntl.h>
#include <unistd.h>

#include "remote/table_mirror.h"

namespace blvd::remote {
using namespace package;
namespace {

std::string hex(uint64_t v, int digits) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "%0*llx", digits, static_cast<unsigned long long>(v));
  return buf;
}

bool linkFailed(core::Status st) { return st == core::Status::Io || st == core::Status::Timeout; }

const SectionInfo* findSection(const std::vector<SectionInfo>& sections, uint32_t tag) {
  for (const SectionInfo& s : sections)
    if (s.tag == tag) return &s;
  return nullptr;
}

// A gap is fetched rather than split into two requests when it costs less than a
// round trip would at a slow link's speed (4 KiB: 100 ms at 320 kbit/s).
constexpr uint64_t kRunGap = 4u << 10, kRunMax = 4u << 20;

}  // namespace

core::Status RemotePackage::fetchChecked(uint64_t offset, uint64_t size, uint32_t crc, const std::string& what,
                                         std::vector<uint8_t>& out, std::string& err) {
  const core::Status st = client_->fetch(offset, size, out, err);
  if (st != core::Status::Ok) return st;
  if (crc32c(out.data(), out.size()) != crc) {
    err = url_ + ": " + what + " at offset " + std::to_string(offset) + ": CRC mismatch";
    out.clear();
    return core::Status::Corrupt;
  }
  return core::Status::Ok;
}

// The first 16 KiB from the server, or from the mirror when offline or when
// the link fails and a mirror is there.
core::Status RemotePackage::readHead(const RemoteOptions& opt, std::vector<uint8_t>& head, uint64_t& file_size,
                                     std::string& err) {
  core::Status st = core::Status::Unavailable;
  if (opt.mode != LinkMode::Offline) {
    st = client_->fetchUpTo(0, kFirstRead, head, err);
    if (st == core::Status::Ok) {
      file_size = client_->resourceBytes() ? client_->resourceBytes() : head.size();
      return st;
    }
    if (!linkFailed(st)) return st;
  }
  if (!mirror_.empty() && readMirrorHead(mirror_, kFirstRead, head, file_size)) {
    offline_start_ = true;
    if (st != core::Status::Unavailable) markLinkDown();
    return core::Status::Ok;
  }
  if (st == core::Status::Unavailable) err = url_ + ": offline, and no tables cached in " + opt.cache_path;
  return st;
}

// The mirror (written unless it is this package's already) and the blob
// index, read from it; without a cache folder, the blob index over the link.
core::Status RemotePackage::openTables(const std::vector<uint8_t>& head, std::string& err) {
  const SectionInfo* bidx = findSection(sections_, kSectionBlobIndex);
  const SectionInfo* bdat = findSection(sections_, kSectionBlobData);
  const uint64_t dir_end = layout_.directory_offset + uint64_t(layout_.directory_count) * kDirEntrySize;
  core::Status st = core::Status::Ok;
  std::vector<uint8_t> index, have;
  uint64_t have_size = 0;
  if (!mirror_.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(std::filesystem::path(mirror_).parent_path(), ec);
    if (ec) return err = mirror_ + ": " + ec.message(), core::Status::Io;
    mirror_bytes_ = mirrorBytes(sections_, head.size());
    const bool same = readMirrorHead(mirror_, dir_end, have, have_size) && have_size == layout_.file_size &&
                      std::equal(have.begin(), have.end(), head.begin(), head.begin() + long(dir_end));
    if (!same && offline_start_) return err = mirror_ + ": not the mirror of " + url_, core::Status::Corrupt;
    // With table page CRCs only TPCR and the blob index now; the other tables a page at a time.
    const SectionInfo* tpcr = findSection(sections_, kSectionTablePages);
    std::vector<SectionInfo> copy = sections_;
    if (tpcr) copy = bidx ? std::vector<SectionInfo>{*tpcr, *bidx} : std::vector<SectionInfo>{*tpcr};
    if (!same && (st = writeMirror(*client_, mirror_, layout_.file_size, head, copy, err)) != core::Status::Ok)
      return st;
    if (tpcr && (st = openTablePages(*tpcr, err)) != core::Status::Ok) return st;
  }
  blobs_.clear();
  if (!bidx || !bdat) return core::Status::Ok;
  if (!mirror_.empty()) {
    if (!readMirror(mirror_, bidx->offset, bidx->size, index) || crc32c(index.data(), index.size()) != bidx->crc)
      return err = mirror_ + ": section BIDX at offset " + std::to_string(bidx->offset) + ": CRC mismatch",
             core::Status::Corrupt;
  } else if ((st = fetchChecked(bidx->offset, bidx->size, bidx->crc, "section BIDX", index, err)) != core::Status::Ok) {
    return st;
  }
  return parseBlobIndex(index.data(), index.size(), *bidx, *bdat, layout_.header.max_blob_contents_bytes, url_, blobs_,
                        err);
}

core::Status RemotePackage::openTablePages(const SectionInfo& tpcr, std::string& err) {
  if (!readMirror(mirror_, tpcr.offset, tpcr.size, tpcr_) || crc32c(tpcr_.data(), tpcr_.size()) != tpcr.crc)
    return err = mirror_ + ": section TPCR at offset " + std::to_string(tpcr.offset) + ": CRC mismatch",
           core::Status::Corrupt;
  const core::Status st = parseTablePages(tpcr_.data(), tpcr_.size(), tpcr.offset, sections_, mirror_, table_pages_, err);
  if (st != core::Status::Ok) return st;
  mirror_fd_ = ::open(mirror_.c_str(), O_RDWR | O_CLOEXEC);
  if (mirror_fd_ < 0) return err = mirror_ + ": cannot open: " + std::strerror(errno), core::Status::Io;
  tables_complete_ = false;
  return core::Status::Ok;
}

RemotePackage::~RemotePackage() {
  if (mirror_fd_ >= 0) ::close(mirror_fd_);
}

bool RemotePackage::pagePresent(const TablePageRun& run, uint32_t k) const {
  thread_local std::vector<uint8_t> buf;
  const uint64_t at = run.section_offset + uint64_t(k) * table_pages_.page_bytes;
  const uint64_t n = std::min<uint64_t>(table_pages_.page_bytes, run.section_offset + run.section_size - at);
  buf.resize(n);
  return readMirrorAt(mirror_fd_, at, n, buf.data()) && crc32c(buf.data(), n) == tablePageCrc(tpcr_.data(), run, k);
}

// Pages [k0, k1) of a run, in one request: each checked, then written (a
// page written twice by two threads gets the same bytes).
core::Status RemotePackage::fetchTablePages(const TablePageRun& run, uint32_t k0, uint32_t k1, std::string& err,
                                            bool background) {
  const uint64_t page = table_pages_.page_bytes, begin = run.section_offset + k0 * page;
  const uint64_t end = std::min(run.section_offset + k1 * page, run.section_offset + run.section_size);
  if (mode() == LinkMode::Offline)
    return err = url_ + ": section " + tagToString(run.tag) + " at offset " + std::to_string(begin) +
                 ": table page not cached and the link is offline",
           core::Status::Unavailable;
  std::vector<uint8_t> bytes;
  core::Status st = onLink(background, end - begin, [&] { return client_->fetch(begin, end - begin, bytes, err); });
  if (st != core::Status::Ok) return st;
  for (uint32_t k = k0; k < k1; ++k) {
    const uint64_t at = (k - k0) * page, n = std::min<uint64_t>(page, bytes.size() - at);
    if (crc32c(bytes.data() + at, n) != tablePageCrc(tpcr_.data(), run, k))
      return err = url_ + ": section " + tagToString(run.tag) + " page " + std::to_string(k) + " at offset " +
                   std::to_string(begin + at) + ": CRC mismatch",
             core::Status::Corrupt;
  }
  if (!writeMirrorAt(mirror_fd_, begin, bytes.data(), bytes.size()))
    return err = mirror_ + ": cannot write " + std::to_string(bytes.size()) + " bytes at offset " +
                 std::to_string(begin) + ": " + std::strerror(errno),
           core::Status::Io;
  table_bytes_.fetch_add(bytes.size(), std::memory_order_relaxed);
  return core::Status::Ok;
}

core::Status RemotePackage::fillTables(std::string& err, const std::function<bool()>& stop) {
  if (mirror_fd_ < 0 || tables_complete_.load(std::memory_order_relaxed)) return core::Status::Ok;
  for (const TablePageRun& run : table_pages_.runs)
    for (uint32_t k = 0; k < run.pages;) {
      if (stop()) return core::Status::Ok;
      if (pagePresent(run, k)) {
        ++k;
        continue;
      }
      uint32_t e = k + 1;
      while (e < run.pages && e - k < kFillPages && !pagePresent(run, e)) ++e;
      const core::Status st = fetchTablePages(run, k, e, err, true);
      if (st != core::Status::Ok) return st;
      k = e;
    }
  tables_complete_.store(true, std::memory_order_relaxed);
  return core::Status::Ok;
}

bool RemotePackage::tablesWanted() const {
  std::lock_guard<std::mutex> lock(wanted_mu_);
  return wanted_n_ > 0;
}

void RemotePackage::clearWantedTables() {
  std::lock_guard<std::mutex> lock(wanted_mu_);
  wanted_n_ = 0;
}

bool RemotePackage::linkDown() const {
  return std::chrono::steady_clock::now().time_since_epoch().count() < link_down_until_.load(std::memory_order_relaxed);
}

void RemotePackage::markLinkDown() {
  const auto until = std::chrono::steady_clock::now() + kLinkDownS;
  link_down_until_.store(until.time_since_epoch().count(), std::memory_order_relaxed);
}

bool RemotePackage::takeWantedTables(uint64_t* offset, uint64_t* size) {
  std::lock_guard<std::mutex> lock(wanted_mu_);
  if (wanted_n_ == 0) return false;
  *offset = wanted_[0].first, *size = wanted_[0].second;
  std::copy(wanted_ + 1, wanted_ + wanted_n_, wanted_);
  --wanted_n_;
  return true;
}

// Whether every page of [offset, offset + size) is in the mirror and whole.
bool RemotePackage::tablesPresent(uint64_t offset, uint64_t size) const {
  const uint64_t page = table_pages_.page_bytes, end = offset + size;
  for (uint64_t at = offset; at < end;) {
    const TablePageRun* run = table_pages_.find(at);
    if (!run) return true;
    const uint64_t run_end = std::min(end, run->section_offset + run->section_size);
    for (uint64_t k = (at - run->section_offset) / page; k <= (run_end - 1 - run->section_offset) / page; ++k)
      if (!pagePresent(*run, uint32_t(k))) return false;
    at = run_end;
  }
  return true;
}

core::Status RemotePackage::askForTables(uint64_t offset, uint64_t size, std::string& err) {
  err = url_ + ": table bytes " + std::to_string(offset) + "-" + std::to_string(offset + size - 1);
  if (mode() == LinkMode::Offline) return err += ": not cached and the link is offline", core::Status::Unavailable;
  if (linkDown()) return err += ": not cached and the link is down", core::Status::Unavailable;
  {
    std::lock_guard<std::mutex> lock(wanted_mu_);
    const auto range = std::make_pair(offset, size);
    if (std::find(wanted_, wanted_ + wanted_n_, range) == wanted_ + wanted_n_ && wanted_n_ < std::size(wanted_))
      wanted_[wanted_n_++] = range;
  }
  if (on_wanted_) on_wanted_();
  return err += ": asked for over the link", core::Status::Unavailable;
}

core::Status RemotePackage::ensureTables(uint64_t offset, uint64_t size, std::string& err, bool wait) {
  if (mirror_fd_ < 0 || size == 0) return core::Status::Ok;
  if (!wait) return tablesPresent(offset, size) ? core::Status::Ok : askForTables(offset, size, err);
  std::lock_guard<std::mutex> lock(table_mu_);
  const uint64_t page = table_pages_.page_bytes, end = offset + size;
  for (uint64_t at = offset; at < end;) {
    const TablePageRun* run = table_pages_.find(at);
    if (!run) return core::Status::Ok;  // TPCR, BIDX: in the mirror since open
    const uint64_t run_end = std::min(end, run->section_offset + run->section_size);
    const uint32_t k1 = uint32_t((run_end - 1 - run->section_offset) / page);
    for (uint32_t k = uint32_t((at - run->section_offset) / page); k <= k1;) {
      if (pagePresent(*run, k)) {
        ++k;
        continue;
      }
      uint32_t e = k + 1;
      while (e <= k1 && !pagePresent(*run, e)) ++e;
      const core::Status st = fetchTablePages(*run, k, e, err);
      if (st != core::Status::Ok) return st;
      k = e;
    }
    at = run_end;
  }
  return core::Status::Ok;
}

core::Status RemotePackage::openCache(const RemoteOptions& opt, std::string& err) {
  if (opt.cache_path.empty()) return core::Status::Ok;
  uint64_t largest = 0;
  for (const BlobInfo& b : blobs_) largest = std::max(largest, b.size);
  const uint64_t need = mirror_bytes_ + DiskCache::kHeaderBytes + largest;
  if (opt.cache_bytes < need)
    return err = opt.cache_path + ": a cache of " + std::to_string(opt.cache_bytes) + " bytes cannot hold " + url_ +
                 "'s tables (" + std::to_string(mirror_bytes_) + " bytes) and its largest blob (" +
                 std::to_string(largest) + "): at least " + std::to_string(need) + " bytes",
           core::Status::InvalidArg;
  cache_ = std::make_unique<DiskCache>();
  return cache_->open(opt.cache_path + "/blobs", opt.cache_bytes - mirror_bytes_, identity_, err);
}

core::Status RemotePackage::open(const std::string& url, const RemoteOptions& opt, std::string& err) {
  url_ = url;
  mirror_ = opt.cache_path.empty() ? "" : opt.cache_path + "/tables.blvd";
  mode_ = opt.mode;
  offline_start_ = false;
  mirror_bytes_ = 0;
  if (mirror_fd_ >= 0) ::close(mirror_fd_);
  mirror_fd_ = -1;
  client_ = std::make_unique<RangeClient>(url, opt.link);
  client_->onAttempt([this](const LinkStats& s) {  // the fetching thread holds link_mu_ or is open()'s
    std::lock_guard<std::mutex> lock(stats_mu_);
    link_stats_ = s;
  });
  cache_.reset();
  std::vector<uint8_t> head;
  uint64_t file_size = 0;
  core::Status st = readHead(opt, head, file_size, err);
  if (st != core::Status::Ok) return st;
  const std::string name = offline_start_ ? mirror_ : url;
  if ((st = parseHeader(head.data(), head.size(), file_size, name, layout_, err)) != core::Status::Ok) return st;
  const uint64_t dir_end = layout_.directory_offset + uint64_t(layout_.directory_count) * kDirEntrySize;
  if (dir_end > head.size())  // the bake puts it in the first 16 KiB; a longer one is read whole
    st = offline_start_ ? (readMirrorHead(mirror_, dir_end, head, file_size) ? st : core::Status::Corrupt)
                        : client_->fetchUpTo(0, dir_end, head, err);
  if (st != core::Status::Ok || head.size() < dir_end) return err = name + ": directory past the end", core::Status::Corrupt;
  const uint8_t* dir = head.data() + layout_.directory_offset;
  if ((st = parseDirectory(dir, dir_end - layout_.directory_offset, layout_, name, sections_, err)) != core::Status::Ok)
    return st;
  identity_ = hex(crc32c(dir, dir_end - layout_.directory_offset, crc32c(head.data(), layout_.header_size)), 8) + "-" +
              hex(file_size, 12);
  st = openTables(head, err);
  {
    std::lock_guard<std::mutex> lock(stats_mu_);
    link_stats_ = client_->stats();
    table_bytes_ = link_stats_.bytes;  // open reads nothing but tables
  }
  return st == core::Status::Ok ? openCache(opt, err) : st;
}

core::Status RemotePackage::section(uint32_t tag, std::vector<uint8_t>& out, std::string& err) {
  const SectionInfo* s = findSection(sections_, tag);
  if (!s) return err = url_ + ": no section " + tagToString(tag), core::Status::NotFound;
  if (!mirror_.empty()) {
    if (!readMirror(mirror_, s->offset, s->size, out) || crc32c(out.data(), out.size()) != s->crc)
      return err = mirror_ + ": section " + tagToString(tag) + " at offset " + std::to_string(s->offset) +
                   ": CRC mismatch",
             core::Status::Corrupt;
    return core::Status::Ok;
  }
  return onLink(false, s->size, [&] { return fetchChecked(s->offset, s->size, s->crc, "section " + tagToString(tag), out, err); });
}

template <typename F>
core::Status RemotePackage::onLink(bool background, uint64_t bytes, F&& f) {
  if (background) {
    while (foreground_.load(std::memory_order_relaxed) > 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  } else {
    foreground_.fetch_add(1, std::memory_order_relaxed);
  }
  core::Status st;
  {
    std::lock_guard<std::mutex> link(link_mu_);
    const auto t0 = std::chrono::steady_clock::now();
    st = f();
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::lock_guard<std::mutex> lock(stats_mu_);
    if (st == core::Status::Ok && s > 0) {
      const double r = double(bytes) / s;
      throughput_bps_ = throughput_bps_ > 0 ? 0.7 * throughput_bps_ + 0.3 * r : r;
    }
    link_stats_ = client_->stats();
    changed_.store(client_->changed(), std::memory_order_relaxed);
  }
  if (linkFailed(st)) markLinkDown();
  if (!background) foreground_.fetch_sub(1, std::memory_order_relaxed);
  return st;
}

core::Status RemotePackage::blob(uint32_t i, std::vector<uint8_t>& out, std::string& err, bool* from_cache) {
  if (i >= blobs_.size()) {
    err = url_ + ": blob " + std::to_string(i) + " does not exist (" + std::to_string(blobs_.size()) + " blobs)";
    return core::Status::NotFound;
  }
  const BlobInfo& b = blobs_[i];
  if (from_cache) *from_cache = false;
  if (cache_) {
    std::lock_guard<std::mutex> lock(cache_mu_);
    if (cache_->get(i, b.crc, out)) {
      if (from_cache) *from_cache = true;
      return core::Status::Ok;
    }
  }
  if (mode() == LinkMode::Offline)
    return err = url_ + ": blob " + std::to_string(i) + " is not cached and the link is offline",
           core::Status::Unavailable;
  const core::Status st =
      onLink(false, b.size, [&] { return fetchChecked(b.offset, b.size, b.crc, "blob " + std::to_string(i), out, err); });
  if (st == core::Status::Ok && cache_) {
    std::lock_guard<std::mutex> lock(cache_mu_);
    cache_->put(i, b.crc, out.data(), out.size());
  }
  return st;
}

// ids[0 .. n) lie in file order with small gaps: one request, split and
// checked blob by blob; a blob whose CRC fails is not cached (Corrupt).
core::Status RemotePackage::fetchRun(const uint32_t* run, size_t n, std::string& err, bool background) {
  const uint64_t begin = blobs_[run[0]].offset, end = blobs_[run[n - 1]].offset + blobs_[run[n - 1]].size;
  std::vector<uint8_t> bytes;
  const core::Status st =
      onLink(background, end - begin, [&] { return client_->fetch(begin, end - begin, bytes, err); });
  if (st != core::Status::Ok) return st;
  std::lock_guard<std::mutex> lock(cache_mu_);
  for (size_t k = 0; k < n; ++k) {
    const BlobInfo& b = blobs_[run[k]];
    const uint8_t* p = bytes.data() + (b.offset - begin);
    if (crc32c(p, b.size) != b.crc)
      return err = url_ + ": blob " + std::to_string(run[k]) + " at offset " + std::to_string(b.offset) +
                   ": CRC mismatch",
             core::Status::Corrupt;
    cache_->put(run[k], b.crc, p, b.size);
  }
  return core::Status::Ok;
}

core::Status RemotePackage::fetchBlobs(const uint32_t* ids, size_t n, std::string& err, bool background) {
  if (!cache_) return core::Status::Ok;  // nowhere to keep them: blob() fetches each
  std::vector<uint32_t> want;
  {
    std::lock_guard<std::mutex> lock(cache_mu_);
    for (size_t k = 0; k < n; ++k)
      if (ids[k] < blobs_.size() && !cache_->contains(ids[k])) want.push_back(ids[k]);
  }
  std::sort(want.begin(), want.end(), [&](uint32_t a, uint32_t b) { return blobs_[a].offset < blobs_[b].offset; });
  want.erase(std::unique(want.begin(), want.end()), want.end());
  if (!want.empty() && mode() == LinkMode::Offline)
    return err = url_ + ": " + std::to_string(want.size()) + " blobs are not cached and the link is offline",
           core::Status::Unavailable;
  for (size_t b = 0; b < want.size();) {
    size_t e = b + 1;
    while (e < want.size() && blobs_[want[e]].offset <= blobs_[want[e - 1]].offset + blobs_[want[e - 1]].size + kRunGap &&
           blobs_[want[e]].offset + blobs_[want[e]].size - blobs_[want[b]].offset <= kRunMax)
      ++e;
    const core::Status st = fetchRun(want.data() + b, e - b, err, background);
    if (st != core::Status::Ok) return st;
    b = e;
  }
  return core::Status::Ok;
}

core::Status RemotePackage::revalidate(std::string& err) {
  if (mode() == LinkMode::Offline) return core::Status::Unavailable;
  std::vector<uint8_t> bytes;
  return onLink(true, 16, [&] { return client_->fetch(0, 16, bytes, err); });
}

bool RemotePackage::cached(uint32_t i) const {
  std::lock_guard<std::mutex> lock(cache_mu_);
  return cache_ && cache_->contains(i);
}

void RemotePackage::pin(const std::vector<uint32_t>& blobs) {
  std::lock_guard<std::mutex> lock(cache_mu_);
  if (cache_) cache_->pin(blobs);
}

double RemotePackage::throughput() const {
  std::lock_guard<std::mutex> lock(stats_mu_);
  return throughput_bps_;
}

RemoteStats RemotePackage::stats() const {
  RemoteStats s;
  {
    std::lock_guard<std::mutex> lock(cache_mu_);
    if (cache_) s.cache = cache_->stats(), s.cache_bytes = cache_->bytes(), s.cache_bytes_max = cache_->maxBytes();
  }
  std::lock_guard<std::mutex> lock(stats_mu_);
  s.link = link_stats_;
  s.changed = changed();
  s.mirror_bytes = mirror_bytes_;
  s.cache_bytes += mirror_bytes_;
  s.throughput_bps = throughput_bps_;
  s.offline_start = offline_start_;
  s.table_bytes = table_bytes_.load(std::memory_order_relaxed);
  return s;
}

}  // namespace blvd::remote
