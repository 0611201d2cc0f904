#include "render/gl_library.h"

#include <dlfcn.h>

#include <mutex>

namespace blvd::render {

namespace {

}  // namespace

bool openLibrary(const char* const* names, const char* const* symbols, void** fns, size_t n, std::string& err) {
  void* lib = nullptr;
  for (const char* const* name = names; *name && !lib; ++name) lib = ::dlopen(*name, RTLD_NOW | RTLD_LOCAL);
  if (!lib) {
    const char* e = ::dlerror();
    err = std::string(names[0]) + ": " + (e ? e : "cannot be opened");
    return false;
  }
  for (size_t i = 0; i < n; ++i) {
    fns[i] = ::dlsym(lib, symbols[i]);
    if (!fns[i]) {
      err = std::string(names[0]) + ": no " + symbols[i];
      return false;  // the library stays open: it may be in use elsewhere in the process
    }
  }
  return true;
}

namespace {
EglApi g_egl{};
}  // namespace

const EglApi* loadEgl(std::string& why) {
  static const char* const names[] = {"libEGL.so.1", "libEGL.so", nullptr};
  // In EglApi's order.
  static const char* const symbols[] = {
      "eglGetError",      "eglGetProcAddress",    "eglQueryString",     "eglInitialize",
      "eglBindAPI",       "eglChooseConfig",      "eglCreateContext",   "eglDestroyContext",
      "eglCreatePbufferSurface", "eglDestroySurface", "eglMakeCurrent", "eglGetCurrentContext",
      "eglGetCurrentDisplay", "eglQueryContext"};
  static_assert(sizeof(symbols) / sizeof(symbols[0]) == sizeof(EglApi) / sizeof(void*), "one name per entry");
  static std::once_flag once;
  static bool ok = false;
  static std::string err;
  std::call_once(once, [] {
    ok = openLibrary(names, symbols, reinterpret_cast<void**>(&g_egl), sizeof(EglApi) / sizeof(void*), err);
  });
  if (ok) return &g_egl;
  why += err + "\n";
  return nullptr;
}

const EglApi& eglApi() { return g_egl; }

}  // namespace blvd::render
