// OSMesa backend: Mesa's pure-software off-screen desktop GL, the fallback when
// no EGL platform works. Kept in its own file because <GL/osmesa.h> pulls in
// <GL/gl.h>, which clashes with the GLES3 declarations of gl_api.h; so this
// file includes only context.h and gl_library.h (EGL's headers) from the module.
#include <GL/osmesa.h>

#include <cstdint>
#include <vector>

#include "render/context.h"
#include "render/gl_library.h"

namespace blvd::render {

namespace {

// libOSMesa, opened at run time (gl_library.h says why).
struct OsmesaApi {
  decltype(&::OSMesaCreateContextAttribs) CreateContextAttribs;
  decltype(&::OSMesaDestroyContext) DestroyContext;
  decltype(&::OSMesaMakeCurrent) MakeCurrent;
  decltype(&::OSMesaGetCurrentContext) GetCurrentContext;
  decltype(&::OSMesaGetProcAddress) GetProcAddress;
};
OsmesaApi g_osmesa{};

const OsmesaApi& osmesa() { return g_osmesa; }

bool loadOsmesa(std::string& why) {
  static const char* const names[] = {"libOSMesa.so.8", "libOSMesa.so", nullptr};
  static const char* const symbols[] = {"OSMesaCreateContextAttribs", "OSMesaDestroyContext", "OSMesaMakeCurrent",
                                        "OSMesaGetCurrentContext", "OSMesaGetProcAddress"};
  static_assert(sizeof(symbols) / sizeof(symbols[0]) == sizeof(OsmesaApi) / sizeof(void*), "one name per entry");
  static LibraryTable table{names, symbols, reinterpret_cast<void**>(&g_osmesa), sizeof(OsmesaApi) / sizeof(void*)};
  return openOnce(table, why);
}

// OSMesaMakeCurrent insists on a colour buffer, so it gets a tiny one; the
// renderer always draws into its own FBO of the requested size.
constexpr int kBufferSize = 4;

class OSMesaGlContext final : public Context {
 public:
  explicit OSMesaGlContext(OSMesaContext ctx)
      : ctx_(ctx), buffer_(size_t{kBufferSize} * kBufferSize * 4) {}
  ~OSMesaGlContext() override {
    // Unbind first: the framebuffer OSMesaMakeCurrent made stays referenced
    // by the thread's binding otherwise and leaks (LeakSanitizer finds it).
    if (osmesa().GetCurrentContext() == ctx_) osmesa().MakeCurrent(nullptr, nullptr, 0, 0, 0);
    osmesa().DestroyContext(ctx_);
  }

  bool makeCurrent() override {
    if (osmesa().GetCurrentContext() == ctx_) return true;
    return osmesa().MakeCurrent(ctx_, buffer_.data(), GL_UNSIGNED_BYTE, kBufferSize,
                             kBufferSize) == GL_TRUE;
  }
  const char* name() const override { return "osmesa"; }
  void* getProcAddress(const char* fn) override {
    return reinterpret_cast<void*>(osmesa().GetProcAddress(fn));
  }
  bool isGles() const override { return false; }

 private:
  OSMesaContext ctx_;
  std::vector<uint8_t> buffer_;
};

}  // namespace

std::unique_ptr<Context> createOSMesaContext(std::string& why) {
  if (std::string e; !loadOsmesa(e)) {
    why += "osmesa: " + e;
    return nullptr;
  }
  // Core 3.3 first: it is what the shaders target. A compatibility context is
  // the fallback for OSMesa builds without core-profile support; the renderer
  // checks that it reaches GL 3.3.
  const int core_attribs[] = {OSMESA_FORMAT,
                              OSMESA_RGBA,
                              OSMESA_DEPTH_BITS,
                              0,  // depth lives in the renderer's FBO
                              OSMESA_PROFILE,
                              OSMESA_CORE_PROFILE,
                              OSMESA_CONTEXT_MAJOR_VERSION,
                              3,
                              OSMESA_CONTEXT_MINOR_VERSION,
                              3,
                              0};
  OSMesaContext ctx = osmesa().CreateContextAttribs(core_attribs, nullptr);
  if (!ctx) {
    const int compat_attribs[] = {OSMESA_FORMAT,  OSMESA_RGBA, OSMESA_DEPTH_BITS,
                                  0,              OSMESA_PROFILE, OSMESA_COMPAT_PROFILE,
                                  0};
    ctx = osmesa().CreateContextAttribs(compat_attribs, nullptr);
  }
  if (!ctx) {
    why += "osmesa: OSMesaCreateContextAttribs failed for core 3.3 and compat\n";
    return nullptr;
  }
  auto out = std::make_unique<OSMesaGlContext>(ctx);
  if (!out->makeCurrent()) {
    why += "osmesa: OSMesaMakeCurrent failed\n";
    return nullptr;
  }
  return out;
}

}  // namespace blvd::render
