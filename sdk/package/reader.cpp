#include "package/reader.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>

#include "package/blob_codec.h"
#include "package/format_detail.h"

namespace blvd::package {

namespace {

std::string crcMismatch(const std::string& name, const std::string& what, uint64_t offset,
                        uint32_t stored, uint32_t computed) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "checksum mismatch (stored 0x%08X, computed 0x%08X)", stored,
                computed);
  return name + ": " + what + " at offset " + std::to_string(offset) + ": " + buf;
}

}  // namespace

PackageReader::~PackageReader() { close(); }

PackageReader::PackageReader(PackageReader&& o) noexcept { *this = std::move(o); }

PackageReader& PackageReader::operator=(PackageReader&& o) noexcept {
  if (this != &o) {
    close();
    data_ = o.data_;
    size_ = o.size_;
    mapped_ = o.mapped_;
    reserved_ = o.reserved_;
    fd_ = o.fd_;
    o.fd_ = -1;
    name_ = std::move(o.name_);
    layout_ = o.layout_;
    sections_ = std::move(o.sections_);
    blobs_ = std::move(o.blobs_);
    table_pages_ = std::move(o.table_pages_);
    has_table_pages_ = o.has_table_pages_;
    o.has_table_pages_ = false;
    o.data_ = nullptr;
    o.size_ = 0;
    o.mapped_ = false;
    o.reserved_ = false;
    o.sections_.clear();
    o.blobs_.clear();
  }
  return *this;
}

void PackageReader::close() {
  if (mapped_ && data_) ::munmap(const_cast<uint8_t*>(data_), size_);
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  data_ = nullptr;
  size_ = 0;
  mapped_ = false;
  reserved_ = false;
  layout_ = HeaderLayout{};
  sections_.clear();
  blobs_.clear();
  has_table_pages_ = false;
}

core::Status PackageReader::open(const std::string& path, PackageReader& out, std::string& err, Access access) {
  out.close();
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    err = path + ": cannot open: " + std::strerror(errno);
    return core::Status::Io;
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    err = path + ": cannot stat: " + std::strerror(errno);
    ::close(fd);
    return core::Status::Io;
  }
  if (!S_ISREG(st.st_mode)) {
    err = path + ": cannot open: not a regular file";
    ::close(fd);
    return core::Status::Io;
  }
  const auto file_size = static_cast<uint64_t>(st.st_size);
  PackageReader r;
  r.name_ = path;
  if (file_size > 0) {
    if (static_cast<uint64_t>(static_cast<size_t>(file_size)) != file_size) {
      ::close(fd);
      err = path + ": file is too large to map on this host";
      return core::Status::Io;
    }
    const bool read_only = access == Access::Read;
    void* p = read_only ? ::mmap(nullptr, static_cast<size_t>(file_size), PROT_NONE,
                                 MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0)
                        : ::mmap(nullptr, static_cast<size_t>(file_size), PROT_READ, MAP_PRIVATE, fd, 0);
    if (p == MAP_FAILED) {
      err = path + ": cannot map " + std::to_string(file_size) + " bytes: " + std::strerror(errno);
      ::close(fd);
      return core::Status::Io;
    }
    r.data_ = static_cast<const uint8_t*>(p);
    r.size_ = static_cast<size_t>(file_size);
    r.mapped_ = true;
    r.reserved_ = read_only;
    r.fd_ = fd;  // read() after open
  } else {
    ::close(fd);
  }
  const core::Status s = r.validate(err);
  if (s != core::Status::Ok) return s;  // r's destructor unmaps
  out = std::move(r);
  return core::Status::Ok;
}

PackageReader PackageReader::openOrThrow(const std::string& path) {
  PackageReader r;
  std::string err;
  const core::Status s = open(path, r, err);
  if (s != core::Status::Ok) throw core::Error(s, err);
  return r;
}

core::Status PackageReader::openMemory(const uint8_t* data, size_t size, const std::string& name,
                                       PackageReader& out, std::string& err) {
  out.close();
  if (data == nullptr && size != 0) {
    err = name + ": null data with nonzero size";
    return core::Status::Misuse;
  }
  PackageReader r;
  r.name_ = name;
  r.data_ = data;
  r.size_ = size;
  const core::Status s = r.validate(err);
  if (s != core::Status::Ok) {
    r.data_ = nullptr;  // not ours: nothing to unmap
    return s;
  }
  out = std::move(r);
  return core::Status::Ok;
}

// The header's bytes: its first kHeaderSize, or the size it states when a
// later minor grew it (up to 64 KiB; parseHeader refuses a larger one).
core::Status PackageReader::readHeader(std::vector<uint8_t>& bytes, std::string& err) const {
  bytes.resize(std::min<size_t>(size_, kHeaderSize));
  if (bytes.empty()) return core::Status::Ok;  // an empty file: parseHeader says so
  core::Status s = read(0, bytes.size(), bytes.data(), err);
  if (s != core::Status::Ok || bytes.size() < kHeaderSize) return s;
  uint32_t stated = 0;
  std::memcpy(&stated, bytes.data() + detail::hdr::kHeaderSize, sizeof stated);
  const size_t want = std::min<size_t>({size_, stated, size_t{64} << 10});
  if (want <= bytes.size()) return s;
  bytes.resize(want);
  return read(0, want, bytes.data(), err);
}

// Header, directory, blob index and table page CRCs, each read (never
// touched through the mapping), parsed and checked.
core::Status PackageReader::validate(std::string& err) {
  std::vector<uint8_t> bytes;
  core::Status s = readHeader(bytes, err);
  if (s != core::Status::Ok) return s;
  if ((s = parseHeader(bytes.data(), bytes.size(), size_, name_, layout_, err)) != core::Status::Ok) return s;
  const size_t dir_size = size_t{layout_.directory_count} * kDirEntrySize;
  bytes.resize(dir_size);
  if ((s = read(layout_.directory_offset, dir_size, bytes.data(), err)) != core::Status::Ok) return s;
  s = parseDirectory(bytes.data(), dir_size, layout_, name_, sections_, err);
  if (s != core::Status::Ok) return s;
  const SectionInfo* index = nullptr;
  const SectionInfo* blob_data = nullptr;
  for (const SectionInfo& si : sections_) {
    if (si.tag == kSectionBlobIndex) index = &si;
    if (si.tag == kSectionBlobData) blob_data = &si;
  }
  if (index) {
    if (!blob_data) {
      err = name_ + ": section " + tagToString(kSectionBlobIndex) + " at offset " +
            std::to_string(index->offset) + ": blob index without a " +
            tagToString(kSectionBlobData) + " section";
      return core::Status::Corrupt;
    }
    if ((s = copy(section(kSectionBlobIndex), bytes, err)) != core::Status::Ok) return s;
    s = parseBlobIndex(bytes.data(), bytes.size(), *index, *blob_data, layout_.header.max_blob_contents_bytes, name_,
                       blobs_, err);
    if (s != core::Status::Ok) return s;
  }
  has_table_pages_ = false;
  if (const Span t = section(kSectionTablePages); t.data) {
    if ((s = copy(t, bytes, err)) != core::Status::Ok) return s;
    if ((s = parseTablePages(bytes.data(), t.size, t.offset, sections_, name_, table_pages_, err)) != core::Status::Ok)
      return s;
    has_table_pages_ = true;
  }
  return core::Status::Ok;
}

bool PackageReader::hasSection(uint32_t tag) const { return find(tag) != nullptr; }

Span PackageReader::section(uint32_t tag) const {
  const SectionInfo* s = find(tag);
  return s ? Span{data_ + s->offset, static_cast<size_t>(s->size), s->offset} : Span{};
}

const SectionInfo* PackageReader::find(uint32_t tag) const {
  for (const SectionInfo& s : sections_)
    if (s.tag == tag) return &s;
  return nullptr;
}

core::Status PackageReader::checkedSection(uint32_t tag, Span& out, std::string& err) const {
  out = Span{};
  if (!isOpen()) {
    err = "package reader is not open";
    return core::Status::Misuse;
  }
  const SectionInfo* s = find(tag);
  if (!s) {
    err = name_ + ": no section " + tagToString(tag);
    return core::Status::NotFound;
  }
  uint32_t crc = 0;
  uint8_t piece[16 * 1024];  // read in pieces: a CRC needs no copy of the section
  for (uint64_t at = 0; at < s->size; at += sizeof piece) {
    const size_t n = static_cast<size_t>(std::min<uint64_t>(sizeof piece, s->size - at));
    const core::Status st = read(s->offset + at, n, piece, err);
    if (st != core::Status::Ok) return st;
    crc = crc32c(piece, n, crc);
  }
  if (crc != s->crc) {
    err = crcMismatch(name_, "section " + tagToString(tag), s->offset, s->crc, crc);
    return core::Status::Corrupt;
  }
  out = Span{data_ + s->offset, static_cast<size_t>(s->size), s->offset};
  return core::Status::Ok;
}

core::Status PackageReader::copy(const Span& s, std::vector<uint8_t>& out, std::string& err, size_t limit) const {
  out.resize(std::min(s.size, limit));
  return read(s.offset, out.size(), out.data(), err);
}

core::Status PackageReader::checkedCopy(uint32_t tag, std::vector<uint8_t>& out, Span& where, std::string& err) const {
  where = Span{};
  const SectionInfo* s = find(tag);
  if (!s) {
    err = name_ + ": no section " + tagToString(tag);
    return core::Status::NotFound;
  }
  const core::Status st = copy(Span{nullptr, static_cast<size_t>(s->size), s->offset}, out, err);
  if (st != core::Status::Ok) return st;
  const uint32_t crc = crc32c(out.data(), out.size());
  if (crc != s->crc) {
    err = crcMismatch(name_, "section " + tagToString(tag), s->offset, s->crc, crc);
    return core::Status::Corrupt;
  }
  where = Span{out.data(), out.size(), s->offset};
  return core::Status::Ok;
}

core::Status PackageReader::blobExists(uint32_t i, std::string& err) const {
  if (!isOpen()) {
    err = "package reader is not open";
    return core::Status::Misuse;
  }
  if (i >= blobs_.size()) {
    err = name_ + ": blob " + std::to_string(i) + " does not exist (package has " +
          std::to_string(blobs_.size()) + ")";
    return core::Status::NotFound;
  }
  return core::Status::Ok;
}

core::Status PackageReader::checkBlob(uint32_t i, const uint8_t* bytes, Span& out, std::string& err) const {
  const BlobInfo& b = blobs_[i];
  const uint32_t crc = crc32c(bytes, static_cast<size_t>(b.size));
  if (crc != b.crc) {
    err = crcMismatch(name_, "blob " + std::to_string(i), b.offset, b.crc, crc);
    return core::Status::Corrupt;
  }
  out = Span{bytes, static_cast<size_t>(b.size), b.offset};
  return core::Status::Ok;
}

core::Status PackageReader::mapped(std::string& err) const {
  if (!reserved_) return core::Status::Ok;
  err = name_ + ": opened to be read, not mapped: its bytes come through read()";
  return core::Status::Misuse;
}

core::Status PackageReader::blob(uint32_t i, Span& out, std::string& err) const {
  out = Span{};
  core::Status st = blobExists(i, err);
  if (st == core::Status::Ok) st = mapped(err);
  if (st != core::Status::Ok) return st;
  return checkBlob(i, data_ + blobs_[i].offset, out, err);
}

core::Status PackageReader::readBlob(uint32_t i, std::vector<uint8_t>& into, Span& out, std::string& err) const {
  out = Span{};
  core::Status st = blobExists(i, err);
  if (st != core::Status::Ok) return st;
  const BlobInfo& b = blobs_[i];
  if (into.size() < b.size) into.resize(static_cast<size_t>(b.size));
  if ((st = read(b.offset, static_cast<size_t>(b.size), into.data(), err)) != core::Status::Ok) {
    err += " (blob " + std::to_string(i) + ")";
    return st;
  }
  return checkBlob(i, into.data(), out, err);
}

core::Status PackageReader::blobContents(uint32_t i, std::vector<uint8_t>& into, Span& out, std::string& err) const {
  Span stored;
  const core::Status st = blob(i, stored, err);
  if (st != core::Status::Ok) return st;
  return unpackBlob(blobs_[i], i, stored.data, into, out, name_, err);
}

core::Status PackageReader::readBlobContents(uint32_t i, std::vector<uint8_t>& into, Span& out,
                                             std::string& err) const {
  out = Span{};
  core::Status st = blobExists(i, err);
  if (st != core::Status::Ok) return st;
  std::vector<uint8_t>& stored_bytes = storedBuffer(blobs_[i], into);
  Span stored;
  if ((st = readBlob(i, stored_bytes, stored, err)) != core::Status::Ok) return st;
  return unpackBlob(blobs_[i], i, stored.data, into, out, name_, err);
}

core::Status PackageReader::read(uint64_t offset, size_t size, uint8_t* dst, std::string& err) const {
  if (!isOpen() || offset > size_ || size > size_ - offset) {
    err = name_ + ": read of " + std::to_string(size) + " bytes at offset " + std::to_string(offset) +
          " is outside the package's " + std::to_string(size_) + " bytes";
    return core::Status::Misuse;
  }
  if (fd_ < 0) {
    if (size) std::memcpy(dst, data_ + offset, size);
    return core::Status::Ok;
  }
  size_t done = 0;
  while (done < size) {
    const ssize_t n = ::pread(fd_, dst + done, size - done, static_cast<off_t>(offset + done));
    if (n > 0) {
      done += static_cast<size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    struct stat st {};
    const std::string why = n < 0 ? std::strerror(errno)
                            : ::fstat(fd_, &st) == 0
                                ? "the file ends at offset " + std::to_string(st.st_size) + ", it had " +
                                      std::to_string(size_) + " bytes when opened (truncated)"
                                : "the file ends early (truncated)";
    err = name_ + ": cannot read " + std::to_string(size) + " bytes at offset " + std::to_string(offset) + ": " + why;
    return core::Status::Io;
  }
  return core::Status::Ok;
}

// Every table page against its CRC in TPCR (the sections' own CRCs passed:
// a mismatch here is a wrong TPCR).
core::Status PackageReader::verifyTablePages(std::string& err) const {
  if (!has_table_pages_) return core::Status::Ok;
  const Span t = section(kSectionTablePages);
  const uint32_t page = table_pages_.page_bytes;
  for (const TablePageRun& r : table_pages_.runs)
    for (uint32_t k = 0; k < r.pages; ++k) {
      const uint64_t at = r.section_offset + uint64_t(k) * page;
      const uint32_t want = tablePageCrc(t.data, r, k);
      const uint32_t got = crc32c(data_ + at, static_cast<size_t>(std::min<uint64_t>(page, r.section_offset + r.section_size - at)));
      if (got != want) {
        err = crcMismatch(name_, "section " + tagToString(r.tag) + " page " + std::to_string(k), at, want, got);
        return core::Status::Corrupt;
      }
    }
  return core::Status::Ok;
}

core::Status PackageReader::verify(std::string& err) const {
  if (!isOpen()) {
    err = "package reader is not open";
    return core::Status::Misuse;
  }
  if (const core::Status st = mapped(err); st != core::Status::Ok) return st;
  // Header and directory were checked at open; checking again costs nothing
  // and keeps verify() a complete statement on its own.
  HeaderLayout layout;
  core::Status s = parseHeader(data_, size_, size_, name_, layout, err);
  if (s != core::Status::Ok) return s;
  std::vector<SectionInfo> sections;
  s = parseDirectory(data_ + layout.directory_offset, size_t{layout.directory_count} * kDirEntrySize,
                     layout, name_, sections, err);
  if (s != core::Status::Ok) return s;
  for (const SectionInfo& si : sections) {
    const uint32_t crc = crc32c(data_ + si.offset, static_cast<size_t>(si.size));
    if (crc != si.crc) {
      err = crcMismatch(name_, "section " + tagToString(si.tag), si.offset, si.crc, crc);
      return core::Status::Corrupt;
    }
  }
  if ((s = verifyTablePages(err)) != core::Status::Ok) return s;
  Span unused;
  for (uint32_t i = 0; i < blobs_.size(); ++i) {
    s = blob(i, unused, err);
    if (s != core::Status::Ok) return s;
  }
  // Bytes outside header, directory and sections must be zero padding: they
  // are under no checksum, so this is the only way a flip there shows.
  struct Range {
    uint64_t begin, end;
  };
  std::vector<Range> used;
  used.push_back({0, layout.header_size});
  used.push_back({layout.directory_offset,
                  layout.directory_offset + uint64_t{layout.directory_count} * kDirEntrySize});
  for (const SectionInfo& si : sections) used.push_back({si.offset, si.offset + si.size});
  std::sort(used.begin(), used.end(), [](const Range& a, const Range& b) { return a.begin < b.begin; });
  uint64_t pos = 0;
  auto checkGap = [&](uint64_t end) -> bool {
    for (uint64_t p = pos; p < end; ++p)
      if (data_[p] != 0) {
        err = name_ + ": padding at offset " + std::to_string(p) +
              ": nonzero byte outside every section";
        return false;
      }
    return true;
  };
  for (const Range& r : used) {
    if (r.begin > pos && !checkGap(r.begin)) return core::Status::Corrupt;
    pos = std::max(pos, r.end);
  }
  if (!checkGap(size_)) return core::Status::Corrupt;
  return core::Status::Ok;
}

}  // namespace blvd::package
