// The project's only stb_image implementation (decoding: the runtime's
// impostor textures, and PNG reading in sdk/imaging). Every other file
// includes the header without the IMPLEMENTATION macro; a second definition
// would be a duplicate symbol. stb_image_write's is sdk/imaging/stb_write_impl.cpp
// (tools only, not in libblvd). Its allocations go through stb_alloc.h.
#include <cstdlib>

#include "render/stb_alloc.h"

namespace blvd::render {
namespace {
thread_local bool t_failed = false;
}
void* stbMalloc(size_t bytes) {
  void* p = std::malloc(bytes);
  t_failed |= p == nullptr;
  return p;
}
void* stbRealloc(void* p, size_t bytes) {
  void* q = std::realloc(p, bytes);
  t_failed |= q == nullptr;
  return q;
}
bool stbAllocFailed() { return t_failed; }
void stbAllocReset() { t_failed = false; }
}  // namespace blvd::render

#define STBI_MALLOC(sz) blvd::render::stbMalloc(sz)
#define STBI_REALLOC(p, newsz) blvd::render::stbRealloc(p, newsz)
#define STBI_FREE(p) std::free(p)
#define STB_IMAGE_IMPLEMENTATION

#define BLVD_STB_IMAGE
#include "core/third_party_stb.h"
