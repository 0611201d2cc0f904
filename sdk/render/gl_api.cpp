// Fills GlApi from a context's getProcAddress.
#include "render/gl_api.h"

#include "render/context.h"

namespace blvd::render {

bool GlApi::load(Context& ctx, std::string& missing) {
  missing.clear();
  // getProcAddress returns void*; converting it to a function pointer is
  // conditionally supported in C++ and fine on every POSIX platform (dlsym).
#define BLVD_GL_LOAD(type, fn)                                        \
  fn = reinterpret_cast<type>(ctx.getProcAddress("gl" #fn));          \
  if (!fn) {                                                          \
    if (!missing.empty()) missing += ' ';                             \
    missing += "gl" #fn;                                              \
  }
  BLVD_GL_FUNCTIONS(BLVD_GL_LOAD)
#undef BLVD_GL_LOAD
  ClearDepthf = reinterpret_cast<PFNGLCLEARDEPTHFPROC>(ctx.getProcAddress("glClearDepthf"));
  DepthRangef = reinterpret_cast<PFNGLDEPTHRANGEFPROC>(ctx.getProcAddress("glDepthRangef"));
  DepthRange = reinterpret_cast<decltype(DepthRange)>(ctx.getProcAddress("glDepthRange"));
  GetTexLevelParameteriv =
      reinterpret_cast<decltype(GetTexLevelParameteriv)>(ctx.getProcAddress("glGetTexLevelParameteriv"));
  TexStorage2D = reinterpret_cast<PFNGLTEXSTORAGE2DPROC>(ctx.getProcAddress("glTexStorage2D"));
  CompressedTexSubImage2D =
      reinterpret_cast<PFNGLCOMPRESSEDTEXSUBIMAGE2DPROC>(ctx.getProcAddress("glCompressedTexSubImage2D"));
  return missing.empty();
}

}  // namespace blvd::render
