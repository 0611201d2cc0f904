// Backend selection: the Auto order and the BLVD_BACKEND override.
#include "render/context.h"

#include <cstdlib>
#include <cstring>

namespace blvd::render {

Context::~Context() = default;

const char* backendName(Backend b) {
  switch (b) {
    case Backend::Auto: return "auto";
    case Backend::EglSurfaceless: return "egl-surfaceless";
    case Backend::EglDevice: return "egl-device";
    case Backend::OSMesa: return "osmesa";
    case Backend::Shared: return "shared";
  }
  return "unknown";
}

bool parseBackend(const char* s, Backend& out) {
  if (!s) return false;
  for (Backend b : {Backend::Auto, Backend::EglSurfaceless, Backend::EglDevice, Backend::OSMesa,
                    Backend::Shared}) {
    if (std::strcmp(s, backendName(b)) == 0) {
      out = b;
      return true;
    }
  }
  return false;
}

std::unique_ptr<Context> createContext(Backend b, std::string& why) {
  if (b == Backend::Auto) {
    // The override only narrows Auto: an explicit request from the host wins.
    const char* env = std::getenv("BLVD_BACKEND");
    if (env && *env) {
      Backend forced = Backend::Auto;
      if (!parseBackend(env, forced)) {
        why += "auto: BLVD_BACKEND=";
        why += env;
        why += " names no backend (egl-surfaceless, egl-device, osmesa, shared)\n";
        return nullptr;
      }
      b = forced;
    }
  }
  switch (b) {
    case Backend::EglSurfaceless: return createEglSurfacelessContext(why);
    case Backend::EglDevice: return createEglDeviceContext(why, false);
    case Backend::OSMesa: return createOSMesaContext(why);
    case Backend::Shared: return createSharedContext(why);
    case Backend::Auto: break;
  }
  // A hardware EGL device goes first: the surfaceless platform goes to
  // whichever vendor glvnd asks first, which on a box with both Mesa and a GPU
  // driver can be llvmpipe, leaving the GPU idle. An explicit non-software
  // device cannot be. Without a GPU this costs one eglQueryDevicesEXT call.
  // (Checked on an H100 with NVIDIA 580: Auto picks egl-device on the GPU.)
  if (auto ctx = createEglDeviceContext(why, true)) return ctx;
  if (auto ctx = createEglSurfacelessContext(why)) return ctx;
  if (auto ctx = createEglDeviceContext(why, false)) return ctx;
  return createOSMesaContext(why);
}

}  // namespace blvd::render
