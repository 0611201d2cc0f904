#include "cli/malloc_probe.h"
#include "cli/driver_libraries.h"

#include <cerrno>
#include <cstddef>
#include <cstring>

#include <dlfcn.h>
#include <execinfo.h>

#include <initializer_list>

#if defined(__SANITIZE_ADDRESS__)  // GCC
#define BLVD_HOOK_MALLOC 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)  // clang
#define BLVD_HOOK_MALLOC 0
#endif
#endif
#ifndef BLVD_HOOK_MALLOC
#define BLVD_HOOK_MALLOC 1
#endif

namespace {
thread_local int t_active = 0;
thread_local bool t_inside = false;
thread_local long t_count = 0, t_driver = 0;
thread_local bool t_failing = false, t_failed = false, t_c_only = false;  // ThreadMallocFailer
thread_local long t_fail_count = 0, t_fail_at = -1;

// Whether the call came through operator new (a C++ allocation): its frame,
// just above malloc's, is named _Znw... / _Zna... (libstdc++'s or a test's
// replacement, which the executable exports because libraries refer to it).
bool throughOperatorNew(void* const* frames, int n) {
  for (int i = 1; i < n && i < 4; ++i) {
    Dl_info info;
    if (dladdr(frames[i], &info) && info.dli_sname &&
        (std::strncmp(info.dli_sname, "_Znw", 4) == 0 || std::strncmp(info.dli_sname, "_Zna", 4) == 0))
      return true;
  }
  return false;
}

// Counts the call; true when a ThreadMallocFailer wants it to fail.
inline bool note() {
  if ((!t_active && !t_failing) || t_inside) return false;
  t_inside = true;  // backtrace and dladdr must not count themselves
  void* frames[24];
  const int n = backtrace(frames, 24);
  bool driver = false;
  for (int i = 1; i < n && !driver; ++i) {
    Dl_info info;
    if (dladdr(frames[i], &info)) driver = blvd::probe::isDriverLibrary(info.dli_fname);
  }
  if (t_active) ++(driver ? t_driver : t_count);
  const bool skip = driver || (t_failing && t_c_only && throughOperatorNew(frames, n));
  t_inside = false;
  if (!t_failing || skip) return false;
  const bool fail = t_fail_count++ == t_fail_at;
  t_failed |= fail;
  if (fail) errno = ENOMEM;
  return fail;
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
  if (note()) return nullptr;
  return __libc_malloc(n);
}
void* calloc(size_t n, size_t m) {
  if (note()) return nullptr;
  return __libc_calloc(n, m);
}
void* realloc(void* p, size_t n) {
  if (note()) return nullptr;  // p stays the caller's
  return __libc_realloc(p, n);
}
void free(void* p) { __libc_free(p); }
void* memalign(size_t a, size_t n) {
  if (note()) return nullptr;
  return __libc_memalign(a, n);
}
void* aligned_alloc(size_t a, size_t n) {
  if (note()) return nullptr;
  return __libc_memalign(a, n);
}
int posix_memalign(void** out, size_t a, size_t n) {
  if (note()) return ENOMEM;
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

ThreadMallocFailer::ThreadMallocFailer(long fail_at, bool c_only) {
  void* frames[2];
  backtrace(frames, 2);  // as above: libgcc_s loaded outside the count
  t_fail_count = 0;
  t_fail_at = fail_at;
  t_failed = false;
  t_c_only = c_only;
  t_failing = true;
}
ThreadMallocFailer::~ThreadMallocFailer() { t_failing = false; }
long ThreadMallocFailer::count() const { return t_fail_count; }
bool ThreadMallocFailer::failed() const { return t_failed; }

}  // namespace blvd::probe
