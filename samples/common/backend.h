// The --backend option of the samples that render: its names and the
// blvd_backend each selects.
#pragma once

#include <string>
#include <vector>

#include "blvd/blvd.h"

namespace samples {

// "auto", "surfaceless", "device", "osmesa": for CLI::IsMember.
inline std::vector<std::string> backendNames() { return {"auto", "surfaceless", "device", "osmesa"}; }

// The backend a name selects; BLVD_BACKEND_AUTO for "auto" and any other name.
inline blvd_backend parseBackend(const std::string& s) {
  if (s == "surfaceless") return BLVD_BACKEND_EGL_SURFACELESS;
  if (s == "device") return BLVD_BACKEND_EGL_DEVICE;
  if (s == "osmesa") return BLVD_BACKEND_OSMESA;
  return BLVD_BACKEND_AUTO;
}

}  // namespace samples
