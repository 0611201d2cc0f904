// A package over range requests; the contract is in remote_package.h.
#include "remote/remote_package.h"

#include <algorithm>
#include <cstdio>

namespace blvd::remote {
using namespace package;
namespace {

std::string hex(uint64_t v, int digits) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "%0*llx", digits, static_cast<unsigned long long>(v));
  return buf;
}

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

core::Status RemotePackage::open(const std::string& url, const RemoteOptions& opt, std::string& err) {
  url_ = url;
  client_ = std::make_unique<RangeClient>(url, opt.link);
  cache_.reset();
  std::vector<uint8_t> first;
  // The first read learns the file's size (Content-Range's total).
  core::Status st = client_->fetchUpTo(0, kFirstRead, first, err);
  if (st != core::Status::Ok) return st;
  const uint64_t file_size = client_->resourceBytes() ? client_->resourceBytes() : first.size();
  if ((st = parseHeader(first.data(), first.size(), file_size, url, layout_, err)) != core::Status::Ok) return st;
  const uint64_t dir_end = layout_.directory_offset + uint64_t(layout_.directory_count) * kDirEntrySize;
  std::vector<uint8_t> dir;
  if (dir_end <= first.size()) {
    dir.assign(first.begin() + long(layout_.directory_offset), first.begin() + long(dir_end));
  } else if ((st = client_->fetch(layout_.directory_offset, dir_end - layout_.directory_offset, dir, err)) !=
             core::Status::Ok) {
    return st;
  }
  if ((st = parseDirectory(dir.data(), dir.size(), layout_, url, sections_, err)) != core::Status::Ok) return st;
  identity_ = hex(crc32c(dir.data(), dir.size(), crc32c(first.data(), layout_.header_size)), 8) + "-" + hex(file_size, 12);
  const auto find = [&](uint32_t tag) {
    return std::find_if(sections_.begin(), sections_.end(), [&](const SectionInfo& s) { return s.tag == tag; });
  };
  const auto bidx = find(kSectionBlobIndex), bdat = find(kSectionBlobData);
  blobs_.clear();
  if (bidx != sections_.end() && bdat != sections_.end()) {
    std::vector<uint8_t> index;
    if ((st = fetchChecked(bidx->offset, bidx->size, bidx->crc, "section BIDX", index, err)) != core::Status::Ok)
      return st;
    if ((st = parseBlobIndex(index.data(), index.size(), *bidx, *bdat, url, blobs_, err)) != core::Status::Ok) return st;
  }
  if (!opt.cache_path.empty()) {
    cache_ = std::make_unique<DiskCache>();
    if ((st = cache_->open(opt.cache_path, opt.cache_bytes, identity_, err)) != core::Status::Ok) return st;
  }
  return core::Status::Ok;
}

core::Status RemotePackage::section(uint32_t tag, std::vector<uint8_t>& out, std::string& err) {
  for (const SectionInfo& s : sections_)
    if (s.tag == tag) return fetchChecked(s.offset, s.size, s.crc, "section " + tagToString(tag), out, err);
  err = url_ + ": no section " + tagToString(tag);
  return core::Status::NotFound;
}

core::Status RemotePackage::blob(uint32_t i, std::vector<uint8_t>& out, std::string& err, bool* from_cache) {
  if (i >= blobs_.size()) {
    err = url_ + ": blob " + std::to_string(i) + " does not exist (" + std::to_string(blobs_.size()) + " blobs)";
    return core::Status::NotFound;
  }
  const BlobInfo& b = blobs_[i];
  if (from_cache) *from_cache = false;
  if (cache_ && cache_->get(i, b.crc, out)) {
    if (from_cache) *from_cache = true;
    return core::Status::Ok;
  }
  const core::Status st = fetchChecked(b.offset, b.size, b.crc, "blob " + std::to_string(i), out, err);
  if (st == core::Status::Ok && cache_) cache_->put(i, b.crc, out.data(), out.size());
  return st;
}

void RemotePackage::pin(const std::vector<uint32_t>& blobs) {
  if (cache_) cache_->pin(blobs);
}

}  // namespace blvd::remote
