// Little-endian, bounds-checked byte reader/writer used by every binary format
// in blvd (package sections, graph). The reader never reads past its span; a
// short read throws core::Error(Corrupt) naming the section and offset.
#pragma once
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "core/status.h"

namespace blvd::core {

class ByteWriter {
 public:
  template <typename T>
  void put(T v) {
    static_assert(std::is_arithmetic_v<T>, "plain numbers only");
    const auto* p = reinterpret_cast<const uint8_t*>(&v);  // host is little-endian (checked in bytes.cpp)
    buf_.insert(buf_.end(), p, p + sizeof(T));
  }
  void putBytes(const void* data, size_t n) {
    const auto* p = static_cast<const uint8_t*>(data);
    buf_.insert(buf_.end(), p, p + n);
  }
  void align(size_t a) {
    while (buf_.size() % a) buf_.push_back(0);
  }
  size_t size() const { return buf_.size(); }
  std::vector<uint8_t>& bytes() { return buf_; }

 private:
  std::vector<uint8_t> buf_;
};

class ByteReader {
 public:
  // `what` names the data for error messages, e.g. "package section GRPH".
  // `base_offset` is the span's offset in its file, so errors give file offsets.
  ByteReader(const uint8_t* data, size_t size, std::string what, uint64_t base_offset = 0)
      : data_(data), size_(size), what_(std::move(what)), base_(base_offset) {}

  template <typename T>
  T get() {
    static_assert(std::is_arithmetic_v<T>, "plain numbers only");
    need(sizeof(T));
    T v;
    std::memcpy(&v, data_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  // A count that must fit in what is left, given each element takes `elem_bytes`.
  uint32_t getCount(size_t elem_bytes) {
    uint64_t at = pos_;
    uint32_t n = get<uint32_t>();
    if (elem_bytes && static_cast<uint64_t>(n) * elem_bytes > remaining())
      fail("count " + std::to_string(n) + " exceeds the remaining bytes", at);
    return n;
  }
  const uint8_t* getBytes(size_t n) {
    need(n);
    const uint8_t* p = data_ + pos_;
    pos_ += n;
    return p;
  }
  size_t pos() const { return pos_; }
  size_t remaining() const { return size_ - pos_; }
  [[noreturn]] void fail(const std::string& why, uint64_t at) const;
  [[noreturn]] void fail(const std::string& why) const { fail(why, pos_); }

 private:
  void need(size_t n) const {
    if (n > size_ - pos_) fail("truncated: need " + std::to_string(n) + " bytes");
  }
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
  std::string what_;
  uint64_t base_;
};

}  // namespace blvd::core
