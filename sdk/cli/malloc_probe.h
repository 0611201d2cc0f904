// Used by the runtime tests and `blvd bench memory`; ThreadMallocFailer by the
// tests only.
//
// Counts every malloc-family call made on the calling thread while a
// ThreadMallocCounter is alive on it: blvd's own and the GL driver's (the
// "zero heap allocations per frame on the render thread"). The counting
// malloc/calloc/realloc/memalign/posix_memalign/aligned_alloc replace glibc's
// in the executable that links it (malloc_probe.cpp) and forward to glibc's __libc_*
// functions, so every shared library's calls go through them. Not usable
// under AddressSanitizer, which owns malloc: available() is false there.
//
// The GL driver's own calls are told apart and counted separately: a call
// whose stack (up to 24 frames) passes through a GL/EGL/driver library
// (driver_libraries.h: libGL*, libEGL*, libgallium*, *_dri.so, libLLVM* ...) is
// the driver's. llvmpipe, for one, bins every frame into scene blocks it
// mallocs and frees itself; blvd cannot change that and does not claim to.
#pragma once

namespace blvd::probe {

class ThreadMallocCounter {
 public:
  ThreadMallocCounter();
  ~ThreadMallocCounter();
  ThreadMallocCounter(const ThreadMallocCounter&) = delete;
  ThreadMallocCounter& operator=(const ThreadMallocCounter&) = delete;
  long count() const;        // blvd's own (not through the driver)
  long driverCount() const;  // made inside the GL driver
  static bool available();
};

// Makes the n-th malloc-family call of blvd's on this thread (not the GL
// driver's: the same test of the stack as above) return null with ENOMEM
// while it is alive: every C allocation (zstd, libwebp, stb_image) and,
// through operator new, every C++ one of a call can be failed in turn.
// fail_at < 0: count only. c_only: only the calls that do not come through
// operator new (C libraries, and blvd's own malloc). Not available under
// AddressSanitizer.
class ThreadMallocFailer {
 public:
  explicit ThreadMallocFailer(long fail_at, bool c_only = false);
  ~ThreadMallocFailer();
  ThreadMallocFailer(const ThreadMallocFailer&) = delete;
  ThreadMallocFailer& operator=(const ThreadMallocFailer&) = delete;
  long count() const;   // blvd's calls on this thread so far
  bool failed() const;  // the fail_at-th came
};

}  // namespace blvd::probe
