// A package's tables on local disk; the contract is in table_mirror.h.
#include "remote/table_mirror.h"

#include <algorithm>
#include <cerrno>
#include <cstring>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace blvd::remote {
namespace {

constexpr uint64_t kPiece = 4u << 20;

bool pwriteAll(int fd, const uint8_t* p, size_t n, uint64_t at) {
  while (n > 0) {
    const ssize_t w = ::pwrite(fd, p, n, off_t(at));
    if (w <= 0) return false;
    p += w, n -= size_t(w), at += uint64_t(w);
  }
  return true;
}

bool preadAll(int fd, uint8_t* p, size_t n, uint64_t at) {
  while (n > 0) {
    const ssize_t r = ::pread(fd, p, n, off_t(at));
    if (r <= 0) return false;
    p += r, n -= size_t(r), at += uint64_t(r);
  }
  return true;
}

// Fetches [b, e) in pieces and writes each at its offset.
core::Status copyRange(RangeClient& client, int fd, uint64_t b, uint64_t e, const std::string& tmp,
                       std::vector<uint8_t>& buf, std::string& err) {
  for (uint64_t at = b; at < e; at += kPiece) {
    const uint64_t n = std::min(kPiece, e - at);
    const core::Status st = client.fetch(at, n, buf, err);
    if (st != core::Status::Ok) return st;
    if (!pwriteAll(fd, buf.data(), buf.size(), at))
      return err = tmp + ": cannot write " + std::to_string(n) + " bytes at offset " + std::to_string(at) + ": " +
                   std::strerror(errno),
             core::Status::Io;
  }
  return core::Status::Ok;
}

}  // namespace

std::vector<std::pair<uint64_t, uint64_t>> mirrorRanges(const std::vector<package::SectionInfo>& sections,
                                                        uint64_t head) {
  std::vector<std::pair<uint64_t, uint64_t>> r;
  for (const package::SectionInfo& s : sections)
    if (s.tag != package::kSectionBlobData && s.offset + s.size > head)
      r.emplace_back(std::max(s.offset, head), s.offset + s.size);
  std::sort(r.begin(), r.end());
  std::vector<std::pair<uint64_t, uint64_t>> merged;
  for (const auto& x : r) {
    // Sections are 8-byte aligned: padding between two is not worth a request.
    if (!merged.empty() && x.first <= merged.back().second + 64) merged.back().second = std::max(merged.back().second, x.second);
    else merged.push_back(x);
  }
  return merged;
}

uint64_t mirrorBytes(const std::vector<package::SectionInfo>& sections, uint64_t head) {
  uint64_t n = head;
  for (const auto& [b, e] : mirrorRanges(sections, head)) n += e - b;
  return n;
}

core::Status writeMirror(RangeClient& client, const std::string& path, uint64_t file_size,
                         const std::vector<uint8_t>& head, const std::vector<package::SectionInfo>& sections,
                         std::string& err) {
  const std::string tmp = path + ".tmp";
  const int fd = ::open(tmp.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return err = tmp + ": cannot create: " + std::strerror(errno), core::Status::Io;
  core::Status st = core::Status::Ok;
  if (::ftruncate(fd, off_t(file_size)) != 0 || !pwriteAll(fd, head.data(), head.size(), 0)) {
    err = tmp + ": cannot write the package's first " + std::to_string(head.size()) + " bytes: " + std::strerror(errno);
    st = core::Status::Io;
  }
  std::vector<uint8_t> buf;
  for (const auto& [b, e] : mirrorRanges(sections, head.size())) {
    if (st != core::Status::Ok) break;
    st = copyRange(client, fd, b, e, tmp, buf, err);
  }
  if (::close(fd) != 0 && st == core::Status::Ok) err = tmp + ": " + std::strerror(errno), st = core::Status::Io;
  if (st == core::Status::Ok && ::rename(tmp.c_str(), path.c_str()) != 0)
    err = path + ": cannot rename: " + std::strerror(errno), st = core::Status::Io;
  if (st != core::Status::Ok) ::unlink(tmp.c_str());
  return st;
}

bool readMirrorHead(const std::string& path, size_t n, std::vector<uint8_t>& out, uint64_t& file_size) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  struct stat st {};
  bool ok = ::fstat(fd, &st) == 0;
  file_size = ok ? uint64_t(st.st_size) : 0;
  out.resize(std::min<uint64_t>(n, file_size));
  ok = ok && preadAll(fd, out.data(), out.size(), 0);
  ::close(fd);
  return ok;
}

bool readMirror(const std::string& path, uint64_t offset, uint64_t size, std::vector<uint8_t>& out) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  out.resize(size);
  const bool ok = preadAll(fd, out.data(), out.size(), offset);
  ::close(fd);
  return ok;
}

}  // namespace blvd::remote

namespace blvd::remote {

bool readMirrorAt(int fd, uint64_t offset, uint64_t size, uint8_t* out) { return preadAll(fd, out, size, offset); }

bool writeMirrorAt(int fd, uint64_t offset, const uint8_t* p, uint64_t size) { return pwriteAll(fd, p, size, offset); }

}  // namespace blvd::remote
