#include "package/writer.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <limits>

#include "package/format_detail.h"
#include "package/table_pages.h"

namespace blvd::package {

using detail::put;

namespace {

uint64_t alignUp(uint64_t v) { return (v + kAlignment - 1) / kAlignment * kAlignment; }

const uint8_t kZeros[kAlignment] = {};

}  // namespace

struct PackageWriter::Layout {
  std::vector<uint8_t> head;   // header + directory
  std::vector<uint8_t> tpcr;   // table page CRCs, after the sections given
  std::vector<uint64_t> section_offsets;  // the sections given, then TPCR
  std::vector<uint8_t> bidx;   // blob index section bytes
  uint64_t bidx_offset = 0;
  uint64_t bdat_offset = 0;
  uint64_t file_size = 0;
};

void PackageWriter::setHeader(const PackageHeader& header) {
  header_ = header;
  header_.version_major = kVersionMajor;
  header_.version_minor = kVersionMinor;
}

void PackageWriter::addSection(uint32_t tag, std::vector<uint8_t> bytes) {
  if (tag == kSectionBlobIndex || tag == kSectionBlobData || tag == kSectionTablePages)
    throw core::Error(core::Status::InvalidArg,
                      "package section " + tagToString(tag) + " is written by PackageWriter itself");
  for (const Section& s : sections_)
    if (s.tag == tag)
      throw core::Error(core::Status::InvalidArg,
                        "package section " + tagToString(tag) + " was added twice");
  const uint32_t crc = crc32c(bytes.data(), bytes.size());
  sections_.push_back(Section{tag, crc, std::move(bytes)});
}

void PackageWriter::setBlobCompression(int level) {
  checkBlobLevel(level);
  blob_level_ = level;
}

uint32_t PackageWriter::addBlob(std::vector<uint8_t> contents) {
  return addStoredBlob(packBlob(std::move(contents), blob_level_));
}

std::vector<uint8_t> PackageWriter::blobContents(uint32_t i) const {
  const Blob& b = blobs_.at(i);
  const BlobInfo info{b.rel_offset, b.bytes.size(), b.crc, b.flags, b.contents_size};
  std::vector<uint8_t> out;
  Span s;
  std::string err;
  if (unpackBlob(info, i, b.bytes.data(), out, s, "package writer", err) != core::Status::Ok)
    throw core::Error(core::Status::Internal, err);
  if (s.data != out.data()) out.assign(s.data, s.data + s.size);
  return out;
}

uint32_t PackageWriter::addStoredBlob(StoredBlob blob) {
  std::vector<uint8_t>& bytes = blob.bytes;
  if (!validBlobFlags(blob.flags) || ((blob.flags & kBlobZstd) == 0 && blob.contents_size != bytes.size()) ||
      blob.contents_size > kMaxBlobContentsBytes)
    throw core::Error(core::Status::InvalidArg, "package: blob " + std::to_string(blobs_.size()) +
                                                    " has flags " + std::to_string(blob.flags) + " and " +
                                                    std::to_string(blob.contents_size) + " bytes of contents in " +
                                                    std::to_string(bytes.size()));
  if (blobs_.size() >= std::numeric_limits<uint32_t>::max())
    throw core::Error(core::Status::InvalidArg, "package: too many blobs");
  // BDAT's CRC covers the zero padding between blobs as well, so that every
  // byte of the file is under some checksum.
  const uint64_t rel = alignUp(bdat_size_);
  bdat_crc_ = crc32c(kZeros, rel - bdat_size_, bdat_crc_);
  const uint32_t crc = crc32c(bytes.data(), bytes.size());
  bdat_crc_ = crc32c(bytes.data(), bytes.size(), bdat_crc_);
  bdat_size_ = rel + bytes.size();
  blobs_.push_back(Blob{crc, rel, std::move(bytes), blob.flags, blob.contents_size});
  return static_cast<uint32_t>(blobs_.size() - 1);
}

uint64_t PackageWriter::sectionBytes(uint32_t tag) const {
  if (tag == kSectionBlobIndex) return kBlobIndexPrefix + blobs_.size() * uint64_t{kBlobEntrySize};
  if (tag == kSectionBlobData) return bdat_size_;
  if (tag == kSectionTablePages) return tablePages().size();
  for (const Section& s : sections_)
    if (s.tag == tag) return s.bytes.size();
  return 0;
}

std::vector<uint8_t> PackageWriter::tablePages() const {
  std::vector<std::pair<uint32_t, const std::vector<uint8_t>*>> tables;
  for (const Section& s : sections_) tables.emplace_back(s.tag, &s.bytes);
  return encodeTablePages(tables);
}

uint64_t PackageWriter::fileBytes() const { return layout().file_size; }

PackageWriter::Layout PackageWriter::layout() const {
  namespace h = detail::hdr;
  namespace d = detail::dir;
  namespace b = detail::blob;
  Layout L;
  L.tpcr = tablePages();
  const size_t n_dir = sections_.size() + 3;  // + TPCR + BIDX + BDAT
  uint64_t pos = kHeaderSize + n_dir * kDirEntrySize;
  for (const Section& s : sections_) {
    pos = alignUp(pos);
    L.section_offsets.push_back(pos);
    pos += s.bytes.size();
  }
  pos = alignUp(pos);
  L.section_offsets.push_back(pos);
  pos += L.tpcr.size();
  L.bidx_offset = alignUp(pos);
  const uint64_t bidx_size = sectionBytes(kSectionBlobIndex);
  L.bdat_offset = alignUp(L.bidx_offset + bidx_size);
  L.file_size = L.bdat_offset + bdat_size_;

  L.bidx.assign(bidx_size, 0);
  put<uint32_t>(L.bidx.data(), static_cast<uint32_t>(blobs_.size()));
  put<uint32_t>(L.bidx.data() + 4, static_cast<uint32_t>(kBlobEntrySize));
  for (size_t i = 0; i < blobs_.size(); ++i) {
    uint8_t* e = L.bidx.data() + kBlobIndexPrefix + i * kBlobEntrySize;
    put<uint64_t>(e + b::kOffset, L.bdat_offset + blobs_[i].rel_offset);
    put<uint64_t>(e + b::kSize, blobs_[i].bytes.size());
    put<uint32_t>(e + b::kCrc, blobs_[i].crc);
    put<uint32_t>(e + b::kFlags, blobs_[i].flags);
    put<uint64_t>(e + b::kContents, blobs_[i].contents_size);
  }

  L.head.assign(kHeaderSize + n_dir * kDirEntrySize, 0);
  uint8_t* dir = L.head.data() + kHeaderSize;
  auto entry = [&](size_t i, uint32_t tag, uint64_t off, uint64_t size, uint32_t crc) {
    uint8_t* e = dir + i * kDirEntrySize;
    put<uint32_t>(e + d::kTag, tag);
    put<uint64_t>(e + d::kOffset, off);
    put<uint64_t>(e + d::kSize, size);
    put<uint32_t>(e + d::kCrc, crc);
  };
  for (size_t i = 0; i < sections_.size(); ++i)
    entry(i, sections_[i].tag, L.section_offsets[i], sections_[i].bytes.size(), sections_[i].crc);
  const size_t n = sections_.size();
  entry(n, kSectionTablePages, L.section_offsets[n], L.tpcr.size(), crc32c(L.tpcr.data(), L.tpcr.size()));
  entry(n + 1, kSectionBlobIndex, L.bidx_offset, bidx_size, crc32c(L.bidx.data(), L.bidx.size()));
  entry(n + 2, kSectionBlobData, L.bdat_offset, bdat_size_, bdat_crc_);

  uint8_t* hp = L.head.data();
  std::memcpy(hp + h::kMagic, kMagic, sizeof kMagic);
  put<uint16_t>(hp + h::kVersionMajor, kVersionMajor);
  put<uint16_t>(hp + h::kVersionMinor, kVersionMinor);
  put<uint32_t>(hp + h::kHeaderSize, static_cast<uint32_t>(kHeaderSize));
  put<uint64_t>(hp + h::kFileSize, L.file_size);
  put<uint64_t>(hp + h::kDirOffset, kHeaderSize);
  put<uint32_t>(hp + h::kDirCount, static_cast<uint32_t>(n_dir));
  put<uint32_t>(hp + h::kDirCrc, crc32c(dir, n_dir * kDirEntrySize));
  put<double>(hp + h::kOriginLat, header_.origin_lat);
  put<double>(hp + h::kOriginLon, header_.origin_lon);
  put<double>(hp + h::kOriginH, header_.origin_h);
  for (int i = 0; i < 2; ++i) {
    put<float>(hp + h::kBoundsMin + 4 * i, header_.bounds_min[i]);
    put<float>(hp + h::kBoundsMax + 4 * i, header_.bounds_max[i]);
  }
  put<uint32_t>(hp + h::kJunctionCount, header_.junction_count);
  put<uint32_t>(hp + h::kCellCount, header_.cell_count);
  put<uint32_t>(hp + h::kBlockCount, header_.block_count);
  put<uint32_t>(hp + h::kBuildingCount, header_.building_count);
  put<uint64_t>(hp + h::kTriangleCount, header_.triangle_count);
  put<uint32_t>(hp + h::kMaxBlockBlob, header_.max_block_blob_bytes);
  put<uint32_t>(hp + h::kMaxCellBlob, header_.max_cell_blob_bytes);
  put<uint64_t>(hp + h::kSourceBytes, header_.source_bytes);
  put<uint32_t>(hp + h::kMaxBlockLod0Vertices, header_.max_block_lod0_vertices);
  put<uint32_t>(hp + h::kMaxBlockLod0Triangles, header_.max_block_lod0_triangles);
  put<uint32_t>(hp + h::kMaxBlockVertices, header_.max_block_vertices);
  put<uint32_t>(hp + h::kMaxBlockTriangles, header_.max_block_triangles);
  put<uint32_t>(hp + h::kMaxCellLocalBlocks, header_.max_cell_local_blocks);
  put<uint32_t>(hp + h::kMaxCellLocalLod0Vertices, header_.max_cell_local_lod0_vertices);
  put<uint32_t>(hp + h::kMaxCellLocalLod0Triangles, header_.max_cell_local_lod0_triangles);
  put<uint32_t>(hp + h::kMaxCellLocalVertices, header_.max_cell_local_vertices);
  put<uint32_t>(hp + h::kMaxCellLocalTriangles, header_.max_cell_local_triangles);
  put<uint32_t>(hp + h::kMaxCellImpostorLayers, header_.max_cell_impostor_layers);
  put<uint64_t>(hp + h::kMaxCellLocalBlobBytes, header_.max_cell_local_blob_bytes);
  put<uint64_t>(hp + h::kMaxCellImpostorBlobBytes, header_.max_cell_impostor_blob_bytes);
  put<uint64_t>(hp + h::kMaxCellImpostorTextureBytes, header_.max_cell_impostor_texture_bytes);
  put<uint32_t>(hp + h::kMaxCellImpostorVertices, header_.max_cell_impostor_vertices);
  put<uint32_t>(hp + h::kMaxCellImpostorTriangles, header_.max_cell_impostor_triangles);
  put<uint32_t>(hp + h::kMaxImpostorTextureBytes, header_.max_impostor_texture_bytes);
  put<uint16_t>(hp + h::kMaxImpostorTextureWidth, header_.max_impostor_texture_width);
  put<uint16_t>(hp + h::kMaxImpostorTextureHeight, header_.max_impostor_texture_height);
  put<uint16_t>(hp + h::kImpostorAtlasWidth, header_.impostor_atlas_width);
  put<uint16_t>(hp + h::kImpostorAtlasHeight, header_.impostor_atlas_height);
  put<uint16_t>(hp + h::kImpostorAtlasEtc2Height, header_.impostor_atlas_etc2_height);
  uint64_t largest = 0;
  for (const Blob& b : blobs_) largest = std::max(largest, b.contents_size);
  put<uint32_t>(hp + h::kMaxBlobContents, static_cast<uint32_t>(largest));
  put<uint32_t>(hp + h::kCrc, detail::headerCrc(hp, kHeaderSize));
  return L;
}

// Streams the file through `sink(const uint8_t*, size_t)`, so write() never
// holds a second copy of the blobs.
template <typename Sink>
void PackageWriter::emit(Sink&& sink) const {
  const Layout L = layout();
  uint64_t pos = 0;
  auto padTo = [&](uint64_t target) {
    if (target > pos) sink(kZeros, static_cast<size_t>(target - pos));
    pos = target;
  };
  auto out = [&](const std::vector<uint8_t>& v) {
    if (!v.empty()) sink(v.data(), v.size());
    pos += v.size();
  };
  out(L.head);
  for (size_t i = 0; i < sections_.size(); ++i) {
    padTo(L.section_offsets[i]);
    out(sections_[i].bytes);
  }
  padTo(L.section_offsets[sections_.size()]);
  out(L.tpcr);
  padTo(L.bidx_offset);
  out(L.bidx);
  for (const Blob& b : blobs_) {
    padTo(L.bdat_offset + b.rel_offset);
    out(b.bytes);
  }
}

std::vector<uint8_t> PackageWriter::toBytes() const {
  std::vector<uint8_t> v;
  v.reserve(fileBytes());
  emit([&](const uint8_t* p, size_t n) { v.insert(v.end(), p, p + n); });
  return v;
}

void PackageWriter::write(const std::string& path) const {
  // A name of this process's own: two writers of one path (a test's seed
  // written by two fuzz runs at once) each rename a whole file over it.
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    const int e = errno;
    throw core::Error(core::Status::Io, path + ": cannot create " + tmp + ": " + std::strerror(e));
  }
  auto ioError = [&](const std::string& what) {
    return core::Error(core::Status::Io, path + ": " + what + ": " + std::strerror(errno));
  };
  try {
    auto flush = [&](const uint8_t* p, size_t n) {
      while (n > 0) {
        const ssize_t w = ::write(fd, p, n);
        if (w < 0) {
          if (errno == EINTR) continue;
          throw ioError("write to " + tmp + " failed");
        }
        p += w;
        n -= static_cast<size_t>(w);
      }
    };
    // Small pieces (header, padding) are gathered; big blobs go straight through.
    std::vector<uint8_t> buf;
    buf.reserve(1 << 20);
    emit([&](const uint8_t* p, size_t n) {
      if (buf.size() + n > buf.capacity()) {
        flush(buf.data(), buf.size());
        buf.clear();
      }
      if (n >= buf.capacity())
        flush(p, n);
      else
        buf.insert(buf.end(), p, p + n);
    });
    flush(buf.data(), buf.size());
    if (::fsync(fd) != 0) throw ioError("fsync of " + tmp + " failed");
    const int rc = ::close(fd);
    fd = -1;
    if (rc != 0) throw ioError("close of " + tmp + " failed");
    if (::rename(tmp.c_str(), path.c_str()) != 0) throw ioError("cannot rename " + tmp + " over it");
  } catch (...) {
    if (fd >= 0) ::close(fd);
    ::unlink(tmp.c_str());
    throw;
  }
}

}  // namespace blvd::package
