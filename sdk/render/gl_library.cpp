#include "render/gl_library.h"

#include <dlfcn.h>

namespace blvd::render {

namespace {

bool open(const LibraryTable& t, std::string& err) {
  void* lib = nullptr;
  for (const char* const* name = t.names; *name && !lib; ++name) lib = ::dlopen(*name, RTLD_NOW | RTLD_LOCAL);
  if (!lib) {
    const char* e = ::dlerror();
    err = std::string(t.names[0]) + ": " + (e ? e : "cannot be opened");
    return false;
  }
  for (size_t i = 0; i < t.n; ++i) {
    t.fns[i] = ::dlsym(lib, t.symbols[i]);
    if (!t.fns[i]) {
      err = std::string(t.names[0]) + ": no " + t.symbols[i];
      return false;  // the library stays open: it may be in use elsewhere in the process
    }
  }
  return true;
}

EglApi g_egl{};

}  // namespace

bool openOnce(LibraryTable& t, std::string& why) {
  std::call_once(t.once, [&t] { t.ok = open(t, t.err); });
  if (!t.ok) why += t.err + "\n";
  return t.ok;
}

const EglApi* loadEgl(std::string& why) {
  static const char* const names[] = {"libEGL.so.1", "libEGL.so", nullptr};
  // In EglApi's order.
  static const char* const symbols[] = {
      "eglGetError",      "eglGetProcAddress",    "eglQueryString",     "eglInitialize",
      "eglBindAPI",       "eglChooseConfig",      "eglCreateContext",   "eglDestroyContext",
      "eglCreatePbufferSurface", "eglDestroySurface", "eglMakeCurrent", "eglGetCurrentContext",
      "eglGetCurrentDisplay", "eglQueryContext"};
  static_assert(sizeof(symbols) / sizeof(symbols[0]) == sizeof(EglApi) / sizeof(void*), "one name per entry");
  static LibraryTable table{names, symbols, reinterpret_cast<void**>(&g_egl), sizeof(EglApi) / sizeof(void*)};
  return openOnce(table, why) ? &g_egl : nullptr;
}

const EglApi& eglApi() { return g_egl; }

}  // namespace blvd::render
