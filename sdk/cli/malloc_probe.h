// Used by the runtime tests and `blvd bench memory`.
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

}  // namespace blvd::probe
