// The replacement global operator new/delete of the tests: AllocCounter
// (alloc_counter.h) counts the calls, NewFailer (new_failer.h) fails the n-th
// of a thread. One replacement for both, so a test may use either.
#include "alloc_counter.h"
#include "new_failer.h"
#include "cli/driver_libraries.h"

#include <dlfcn.h>
#include <execinfo.h>

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <new>

namespace {

std::atomic<int> g_active{0};
std::atomic<long> g_count{0};

thread_local bool t_active = false, t_inside = false, t_failed = false;
thread_local long t_count = 0, t_fail_at = -1;

// Counts a call of blvd's (not the driver's); true when it is the one to fail.
bool shouldFail() {
  if (!t_active || t_inside) return false;
  t_inside = true;  // backtrace and dladdr must not count themselves
  void* frames[24];
  const int n = backtrace(frames, 24);
  bool driver = false;
  for (int i = 1; i < n && !driver; ++i) {
    Dl_info info{};
    if (dladdr(frames[i], &info)) driver = blvd::probe::isDriverLibrary(info.dli_fname);
  }
  t_inside = false;
  if (driver) return false;
  const bool fail = t_count++ == t_fail_at;
  t_failed |= fail;
  return fail;
}

}  // namespace

void* operator new(std::size_t n) {
  if (g_active.load(std::memory_order_relaxed) > 0) g_count.fetch_add(1, std::memory_order_relaxed);
  if (shouldFail()) throw std::bad_alloc();
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return operator new(n);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept { return operator new(n, std::nothrow); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace blvd_test {

AllocCounter::AllocCounter() {
  g_count = 0;
  g_active.fetch_add(1);
}
AllocCounter::~AllocCounter() { g_active.fetch_sub(1); }
long AllocCounter::count() const { return g_count.load(); }

NewFailer::NewFailer(long fail_at) {
  void* frames[2];
  backtrace(frames, 2);  // the first backtrace() loads libgcc_s: outside the count
  t_count = 0;
  t_failed = false;
  t_fail_at = fail_at;
  t_active = true;
}
NewFailer::~NewFailer() { t_active = false; }
long NewFailer::count() const { return t_count; }
bool NewFailer::failed() const { return t_failed; }

}  // namespace blvd_test
