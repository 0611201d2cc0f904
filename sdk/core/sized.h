// Reading what a C host handed over: public structs only grow at the end
// (STYLE.md), so copy as much of the caller's struct as its struct_size says
// and zero the rest (0 means the current size); and a C enum field may hold
// any int, which C++ must not load as the enum type (undefined outside the
// enum's range), so checks read its raw bits.
#pragma once
#include <cstdint>
#include <cstring>

namespace blvd::core {

template <typename T>
T sized(const T& in) {
  T out{};
  const size_t n = in.struct_size && in.struct_size < sizeof(T) ? in.struct_size : sizeof(T);
  std::memcpy(&out, &in, n);
  return out;
}

// The int a C host stored in an enum field or argument.
template <typename E>
int32_t rawEnum(const E& e) {
  static_assert(sizeof(E) == sizeof(int32_t), "C enums of this API are int-sized");
  int32_t v;
  std::memcpy(&v, &e, sizeof v);
  return v;
}

}  // namespace blvd::core
