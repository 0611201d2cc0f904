// What the C API's fuzz targets share: a script of calls read from the
// fuzzer's bytes, and output structs of the fuzzer's struct_size checked for
// writes past it.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "blvd/blvd.h"

namespace blvd_fuzz {

// Reads the script's bytes in order; zeros once it runs out.
struct Script {
  const uint8_t* p;
  size_t n;
  bool done() const { return n == 0; }
  void take(void* out, size_t size) {
    const size_t k = size < n ? size : n;
    std::memcpy(out, p, k);
    std::memset(static_cast<uint8_t*>(out) + k, 0, size - k);
    p += k;
    n -= k;
  }
  uint8_t byte() {
    uint8_t b;
    take(&b, 1);
    return b;
  }
  template <typename T>
  T in() {  // an input struct with the fuzzer's struct_size (any value: a newer caller's bigger struct too)
    T v;
    take(&v, sizeof v);
    return v;
  }
};

// A status of the enum.
inline bool known(blvd_status s) { return s >= BLVD_OK && s <= BLVD_ERR_OFF_MAP; }

struct OutResult {
  blvd_status status;
  bool whole;  // the struct_size asked for all of T
};

// Calls `call` on an output struct T of the script's struct_size (0: the
// whole struct) in a buffer of canaries: aborts if anything is written past
// it. `v` gets what was written, zeros after.
template <typename T, typename Call>
OutResult callOut(Script& sc, T& v, Call&& call) {
  constexpr size_t kPad = 64;
  uint8_t buf[sizeof(T) + kPad];
  std::memset(buf, 0xA5, sizeof buf);
  const uint32_t size = sc.byte() % (sizeof(T) + 1);
  std::memcpy(buf, &size, sizeof size);
  const blvd_status s = call(reinterpret_cast<T*>(buf));
  const size_t written = size ? size : sizeof(T);
  for (size_t i = written < sizeof size ? sizeof size : written; i < sizeof buf; ++i)
    if (buf[i] != 0xA5) std::abort();
  std::memset(&v, 0, sizeof v);
  std::memcpy(&v, buf, written);
  return {s, written == sizeof(T)};
}

}  // namespace blvd_fuzz
