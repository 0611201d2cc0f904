// Blobs on disk in a fixed number of bytes; the contract is in disk_cache.h.
#include "remote/disk_cache.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/bytes.h"
#include "package/format.h"

namespace blvd::remote {
namespace fs = std::filesystem;
namespace {

constexpr char kMagic[8] = {'B', 'L', 'V', 'D', 'C', 'E', '0', '1'};

struct EntryHeader {
  uint32_t blob = 0, crc = 0;
  uint64_t size = 0;
};

// The entry header's fields from its bytes; false when the magic is not ours.
bool parseHeader(const uint8_t* b, EntryHeader& h) {
  if (std::memcmp(b, kMagic, 8) != 0) return false;
  core::ByteReader r(b + 8, DiskCache::kHeaderBytes - 8, "cache entry header");
  h.blob = r.get<uint32_t>(), h.crc = r.get<uint32_t>(), h.size = r.get<uint64_t>();
  return true;
}

std::vector<uint8_t> headerBytes(const EntryHeader& h) {
  core::ByteWriter w;
  w.putBytes(kMagic, 8);
  w.put(h.blob), w.put(h.crc), w.put(h.size);
  return std::move(w.bytes());
}

bool readHeader(const std::string& path, EntryHeader& h) {
  uint8_t b[DiskCache::kHeaderBytes];
  std::ifstream f(path, std::ios::binary);
  return f.read(reinterpret_cast<char*>(b), sizeof b) && parseHeader(b, h);
}

// Writes all of `n` bytes; false on any error (a full disk).
bool writeAll(int fd, const uint8_t* p, size_t n) {
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w <= 0) return false;
    p += w, n -= size_t(w);
  }
  return true;
}

uint64_t nowNs() {
  timespec t{};
  clock_gettime(CLOCK_REALTIME, &t);
  return uint64_t(t.tv_sec) * 1000000000ull + uint64_t(t.tv_nsec);
}

uint64_t mtimeNs(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return 0;
  return uint64_t(st.st_mtim.tv_sec) * 1000000000ull + uint64_t(st.st_mtim.tv_nsec);
}

}  // namespace

std::string DiskCache::pathOf(uint32_t blob) const { return dir_ + "/" + std::to_string(blob) + ".blob"; }

// Records a use in the entry's mtime, strictly after every earlier one (file
// times are coarser than a cache's uses), so the order survives a restart.
void DiskCache::touch(uint32_t blob) {
  stamp_ = std::max(nowNs(), stamp_ + 1);
  const timespec t{time_t(stamp_ / 1000000000ull), long(stamp_ % 1000000000ull)};
  const timespec times[2] = {t, t};
  ::utimensat(AT_FDCWD, pathOf(blob).c_str(), times, 0);
}

core::Status DiskCache::open(const std::string& dir, uint64_t max_bytes, const std::string& identity, std::string& err) {
  entries_.clear(), pinned_.clear(), bytes_ = 0, clock_ = 0, stamp_ = 0, stats_ = {};
  if (identity.empty() || identity.find('/') != std::string::npos)
    return err = dir + ": cache needs the package's identity", core::Status::InvalidArg;
  if (max_bytes < kHeaderBytes + 1)
    return err = dir + ": cache of " + std::to_string(max_bytes) + " bytes holds no entry", core::Status::InvalidArg;
  max_bytes_ = max_bytes;
  dir_ = dir + "/" + identity;
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec) return err = dir_ + ": " + ec.message(), core::Status::Io;
  for (const auto& other : fs::directory_iterator(dir, ec))  // another package's blobs: never mixed in
    if (other.path().filename() != identity) fs::remove_all(other.path(), ec);
  std::vector<std::pair<uint64_t, uint32_t>> by_use;
  for (const auto& f : fs::directory_iterator(dir_, ec)) {
    const std::string path = f.path().string();
    EntryHeader h;
    const uint64_t size = f.is_regular_file() ? f.file_size(ec) : 0;
    if (f.path().extension() != ".blob" || !readHeader(path, h) || size != kHeaderBytes + h.size ||
        path != pathOf(h.blob)) {
      fs::remove_all(f.path(), ec);  // a temporary left by a killed process, a truncated or foreign file
      ++stats_.dropped;
      continue;
    }
    entries_[h.blob] = {size, 0};
    bytes_ += size;
    by_use.emplace_back(mtimeNs(path), h.blob);
    stamp_ = std::max(stamp_, by_use.back().first);
  }
  if (ec) return err = dir_ + ": " + ec.message(), core::Status::Io;
  std::sort(by_use.begin(), by_use.end());
  for (const auto& [t, blob] : by_use) entries_[blob].used = ++clock_;
  makeRoom(0);  // a smaller max_bytes than the last run's
  return core::Status::Ok;
}

void DiskCache::drop(uint32_t blob, bool bad) {
  const auto it = entries_.find(blob);
  if (it == entries_.end()) return;
  std::error_code ec;
  fs::remove(pathOf(blob), ec);
  bytes_ -= it->second.bytes;
  entries_.erase(it);
  ++(bad ? stats_.dropped : stats_.evictions);
}

bool DiskCache::get(uint32_t blob, uint32_t crc, std::vector<uint8_t>& out) {
  const auto it = entries_.find(blob);
  if (it == entries_.end()) return ++stats_.misses, false;
  std::ifstream f(pathOf(blob), std::ios::binary);
  uint8_t hb[kHeaderBytes];
  EntryHeader h;
  out.resize(it->second.bytes - kHeaderBytes);
  const bool read = f.read(reinterpret_cast<char*>(hb), sizeof hb) &&
                    f.read(reinterpret_cast<char*>(out.data()), std::streamsize(out.size()));
  if (!read || !parseHeader(hb, h) || h.blob != blob || h.crc != crc || package::crc32c(out.data(), out.size()) != crc) {
    drop(blob, true);
    out.clear();
    return ++stats_.misses, false;
  }
  it->second.used = ++clock_;
  touch(blob);
  return ++stats_.hits, true;
}

bool DiskCache::makeRoom(uint64_t need) {
  while (bytes_ + need > max_bytes_) {
    uint32_t victim = 0;
    uint64_t oldest = UINT64_MAX;
    for (const auto& [blob, e] : entries_)
      if (!pinned_.count(blob) && e.used < oldest) oldest = e.used, victim = blob;
    if (oldest == UINT64_MAX) return false;  // only pinned entries left
    drop(victim, false);
  }
  return true;
}

bool DiskCache::put(uint32_t blob, uint32_t crc, const uint8_t* data, size_t size) {
  const uint64_t need = kHeaderBytes + size;
  if (dir_.empty() || package::crc32c(data, size) != crc) return ++stats_.not_cached, false;
  drop(blob, false);
  if (need > max_bytes_ || !makeRoom(need)) return ++stats_.not_cached, false;
  const std::vector<uint8_t> h = headerBytes({blob, crc, size});
  const std::string path = pathOf(blob), tmp = path + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  bool ok = fd >= 0 && writeAll(fd, h.data(), h.size()) && writeAll(fd, data, size);
  if (fd >= 0) ok = ::close(fd) == 0 && ok;
  if (!ok || ::rename(tmp.c_str(), path.c_str()) != 0) {
    ::unlink(tmp.c_str());
    return ++stats_.not_cached, false;
  }
  entries_[blob] = {need, ++clock_};
  bytes_ += need;
  touch(blob);
  return ++stats_.puts, true;
}

void DiskCache::pin(const std::vector<uint32_t>& blobs) { pinned_ = {blobs.begin(), blobs.end()}; }

}  // namespace blvd::remote
