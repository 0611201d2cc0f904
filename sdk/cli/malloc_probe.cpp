#include "cli/malloc_probe.h"
#include "cli/driver_libraries.h"

#include <cerrno>
#include <cstddef>
#include <cstring>

#include <dlfcn.h>
#include <execinfo.h>

#include <initializer_list>

#if defined(__SANITIZE_ADDRESS__)
#define BLVD_HOOK_MALLOC 0
#else
#define BLVD_HOOK_MALLOC 1
#endif

namespace {
thread_local int t_active = 0;
thread_local bool t_inside = false;
thread_local long t_count = 0, t_driver = 0;


inline void note() {
  if (!t_active || t_inside) return;
  t_inside = true;  // backtrace and dladdr must not count themselves
  void* frames[24];
  const int n = backtrace(frames, 24);
  bool driver = false;
  for (int i = 1; i < n && !driver; ++i) {
    Dl_info info;
    if (dladdr(frames[i], &info)) driver = blvd::probe::isDriverLibrary(info.dli_fname);
  }
  ++(driver ? t_driver : t_count);
  t_inside = false;
}
}  // namespace

#if BLVD_HOOK_MALLOC
extern "C" {
void* __libc_malloc(size_t);
void* __libc_calloc(size_t, size_t);
void* __libc_realloc(void*, size_t);
void* __libc_memalign(size_t, size_t);
void __libc_free(void*);

void* malloc(size_t n) {
  note();
  return __libc_malloc(n);
}
void* calloc(size_t n, size_t m) {
  note();
  return __libc_calloc(n, m);
}
void* realloc(void* p, size_t n) {
  note();
  return __libc_realloc(p, n);
}
void free(void* p) { __libc_free(p); }
void* memalign(size_t a, size_t n) {
  note();
  return __libc_memalign(a, n);
}
void* aligned_alloc(size_t a, size_t n) {
  note();
  return __libc_memalign(a, n);
}
int posix_memalign(void** out, size_t a, size_t n) {
  note();
  void* p = __libc_memalign(a, n);
  if (!p) return ENOMEM;
  *out = p;
  return 0;
}
}
#endif

namespace blvd::probe {

ThreadMallocCounter::ThreadMallocCounter() {
  // The first backtrace() loads libgcc_s, which allocates: do it uncounted.
  void* frames[2];
  backtrace(frames, 2);
  t_count = t_driver = 0;
  ++t_active;
}
ThreadMallocCounter::~ThreadMallocCounter() { --t_active; }
long ThreadMallocCounter::count() const { return t_count; }
long ThreadMallocCounter::driverCount() const { return t_driver; }
bool ThreadMallocCounter::available() { return BLVD_HOOK_MALLOC != 0; }

}  // namespace blvd::probe
