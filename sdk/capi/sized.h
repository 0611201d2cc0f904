// Public structs only grow at the end (STYLE.md): copy as much of the caller's
// struct as its struct_size says, zero the rest (0 means the current size).
#pragma once
#include <cstring>

namespace blvd::capi {

template <typename T>
T sized(const T& in) {
  T out{};
  const size_t n = in.struct_size && in.struct_size < sizeof(T) ? in.struct_size : sizeof(T);
  std::memcpy(&out, &in, n);
  return out;
}

}  // namespace blvd::capi
