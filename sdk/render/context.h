// A GL context the renderer can draw with, behind one small interface, so the
// renderer never knows which library (EGL, OSMesa, the host) provides GL.
//
// This header must stay free of GL/EGL/OSMesa headers: osmesa_context.cpp
// includes it next to <GL/osmesa.h>, which pulls <GL/gl.h> and would clash with
// the GLES3 declarations the rest of the module uses.
#pragma once
#include <memory>
#include <string>

namespace blvd::render {

// Values match blvd_backend in include/blvd/blvd.h, so capi casts 1:1.
enum class Backend : int {
  Auto = 0,            // hardware EGL device, EGL surfaceless, any EGL device, OSMesa
  EglSurfaceless = 1,  // EGL_MESA_platform_surfaceless, GLES 3.x, no surface
  EglDevice = 2,       // EGL_EXT_platform_device, GLES 3.x, no surface
  OSMesa = 3,          // Mesa's pure-software off-screen desktop GL 3.3+
  Shared = 4,          // the host's EGL context, current on the calling thread
};

// Short lower-case name ("egl-surfaceless", "egl-device", "osmesa", "shared",
// "auto"); static storage.
const char* backendName(Backend b);

// Parses a backendName(); false when `s` names no backend.
bool parseBackend(const char* s, Backend& out);

class Context {
 public:
  Context() = default;
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
  virtual ~Context();

  // Makes the context current on the calling thread. For Shared it only checks
  // that the adopted context is still the current one.
  virtual bool makeCurrent() = 0;
  // backendName() of the backend that made it.
  virtual const char* name() const = 0;
  // Core and extension GL entry points; nullptr when missing.
  virtual void* getProcAddress(const char* fn) = 0;
  // True for OpenGL ES, false for desktop GL (shaders get a different #version).
  virtual bool isGles() const = 0;
  // True when the host owns the context and its framebuffer: the renderer then
  // draws into whatever framebuffer is bound and restores the state it touches.
  virtual bool isShared() const { return false; }
};

// Creates a context and makes it current on the calling thread. With
// Backend::Auto (order: a hardware EGL device, EGL surfaceless, any EGL device,
// OSMesa), the environment variable BLVD_BACKEND (a backendName()) picks
// one backend instead of trying them in order.
// On failure returns nullptr and `why` lists one line per backend tried, e.g.
// "egl-surfaceless: eglInitialize failed (EGL_NOT_INITIALIZED)".
std::unique_ptr<Context> createContext(Backend b, std::string& why);

// One backend each, for createContext; `why` gets a reason appended on failure.
std::unique_ptr<Context> createEglSurfacelessContext(std::string& why);
std::unique_ptr<Context> createEglDeviceContext(std::string& why, bool hardware_only);
std::unique_ptr<Context> createOSMesaContext(std::string& why);
std::unique_ptr<Context> createSharedContext(std::string& why);

}  // namespace blvd::render
