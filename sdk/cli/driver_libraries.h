// Which shared libraries are the GL driver's (libGL*, libEGL*, libgallium*,
// *_dri.so, libLLVM*, libOSMesa*, libglapi*, libgbm*, libvulkan*): the
// allocation probes tell the driver's calls from blvd's by the libraries on
// the call stack (sdk/cli/malloc_probe.cpp, tests/fault/alloc_counter.cpp).
#pragma once
#include <cstring>
#include <initializer_list>

namespace blvd::probe {

inline bool isDriverLibrary(const char* path) {
  if (!path) return false;
  const char* base = std::strrchr(path, '/');
  base = base ? base + 1 : path;
  for (const char* lib :
       {"libGL", "libEGL", "libgallium", "_dri.so", "libLLVM", "libOSMesa", "libglapi", "libgbm", "libvulkan"})
    if (std::strstr(base, lib)) return true;
  return false;
}

}  // namespace blvd::probe
