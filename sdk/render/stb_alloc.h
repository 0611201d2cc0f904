// stb_image's allocations, through blvd's functions (STBI_MALLOC/STBI_REALLOC
// in stb_impl.cpp), so that a decode that failed for want of memory can be
// told from a bad image: stb_image reports a failed allocation inside its
// format probes as "unknown image type", not "outofmem".
#pragma once
#include <cstddef>

namespace blvd::render {

void* stbMalloc(size_t bytes);
void* stbRealloc(void* p, size_t bytes);
// Whether one of them failed on this thread since the last stbAllocReset().
bool stbAllocFailed();
void stbAllocReset();

}  // namespace blvd::render
