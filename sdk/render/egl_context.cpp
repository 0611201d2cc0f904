// The EGL context used by both EGL backends: one GLES 3.x context, current
// without a surface where the driver allows it. The renderer draws into its
// own FBO, so no window or pbuffer colour buffer is ever needed for output.
#include "render/egl_common.h"

#include <cstring>

namespace blvd::render::egl {

const char* errorName(EGLint code) {
  switch (code) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_CURRENT_SURFACE: return "EGL_BAD_CURRENT_SURFACE";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_NATIVE_PIXMAP: return "EGL_BAD_NATIVE_PIXMAP";
    case EGL_BAD_NATIVE_WINDOW: return "EGL_BAD_NATIVE_WINDOW";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE: return "EGL_BAD_SURFACE";
    case EGL_CONTEXT_LOST: return "EGL_CONTEXT_LOST";
    default: return "unknown EGL error";
  }
}

bool hasExtension(const char* extensions, const char* name) {
  if (!extensions || !name || !*name) return false;
  const size_t n = std::strlen(name);
  for (const char* p = extensions; (p = std::strstr(p, name)) != nullptr; p += n) {
    const bool starts = p == extensions || p[-1] == ' ';
    const bool ends = p[n] == '\0' || p[n] == ' ';
    if (starts && ends) return true;
  }
  return false;
}

void fail(std::string& why, const char* backend, const char* what) {
  why += backend;
  why += ": ";
  why += what;
  why += " failed (";
  why += errorName(eglApi().GetError());
  why += ")\n";
}

namespace {

class EglContext final : public Context {
 public:
  EglContext(EGLDisplay dpy, EGLContext ctx, EGLSurface surf, const char* backend)
      : dpy_(dpy), ctx_(ctx), surf_(surf), backend_(backend) {}

  // The display is deliberately not eglTerminate()d: without
  // EGL_KHR_display_reference (absent in Mesa 22.3) termination is
  // process-wide and would kill any other context on the same display, e.g.
  // a second runtime or the host's own. An initialised display costs little.
  ~EglContext() override {
    if (eglApi().GetCurrentContext() == ctx_) {
      eglApi().MakeCurrent(dpy_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    }
    eglApi().DestroyContext(dpy_, ctx_);
    if (surf_ != EGL_NO_SURFACE) eglApi().DestroySurface(dpy_, surf_);
  }

  bool makeCurrent() override {
    if (eglApi().GetCurrentContext() == ctx_) return true;
    return eglApi().MakeCurrent(dpy_, surf_, surf_, ctx_) == EGL_TRUE;
  }
  const char* name() const override { return backend_; }
  void* getProcAddress(const char* fn) override {
    return reinterpret_cast<void*>(eglApi().GetProcAddress(fn));
  }
  bool isGles() const override { return true; }

 private:
  EGLDisplay dpy_;
  EGLContext ctx_;
  EGLSurface surf_;
  const char* backend_;
};

}  // namespace

std::unique_ptr<Context> createOnDisplay(EGLDisplay dpy, const char* backend, std::string& why) {
  const char* exts = eglApi().QueryString(dpy, EGL_EXTENSIONS);
  const bool surfaceless = hasExtension(exts, "EGL_KHR_surfaceless_context");

  if (eglApi().BindAPI(EGL_OPENGL_ES_API) != EGL_TRUE) {
    fail(why, backend, "eglBindAPI(EGL_OPENGL_ES_API)");
    return nullptr;
  }
  // A config is still needed for the context on drivers without
  // EGL_KHR_no_config_context; ask for pbuffer support so the fallback
  // surface below can be made from the same config.
  const EGLint config_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_ES3_BIT,
                                   EGL_SURFACE_TYPE,    surfaceless ? 0 : EGL_PBUFFER_BIT,
                                   EGL_RED_SIZE,        8,
                                   EGL_GREEN_SIZE,      8,
                                   EGL_BLUE_SIZE,       8,
                                   EGL_NONE};
  EGLConfig config = nullptr;
  EGLint count = 0;
  if (eglApi().ChooseConfig(dpy, config_attribs, &config, 1, &count) != EGL_TRUE || count < 1) {
    if (surfaceless && hasExtension(exts, "EGL_KHR_no_config_context")) {
      config = EGL_NO_CONFIG_KHR;
    } else {
      fail(why, backend, "eglChooseConfig(GLES3)");
      return nullptr;
    }
  }
  // 3.0 is the floor; Mesa hands out the highest compatible version (3.2).
  const EGLint ctx_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 0,
                                EGL_NONE};
  EGLContext ctx = eglApi().CreateContext(dpy, config, EGL_NO_CONTEXT, ctx_attribs);
  if (ctx == EGL_NO_CONTEXT) {
    fail(why, backend, "eglCreateContext(GLES 3.0)");
    return nullptr;
  }
  EGLSurface surf = EGL_NO_SURFACE;
  if (!surfaceless) {
    const EGLint pb_attribs[] = {EGL_WIDTH, 16, EGL_HEIGHT, 16, EGL_NONE};
    surf = config ? eglApi().CreatePbufferSurface(dpy, config, pb_attribs) : EGL_NO_SURFACE;
    if (surf == EGL_NO_SURFACE) {
      fail(why, backend, "eglCreatePbufferSurface (no EGL_KHR_surfaceless_context)");
      eglApi().DestroyContext(dpy, ctx);
      return nullptr;
    }
  }
  auto out = std::make_unique<EglContext>(dpy, ctx, surf, backend);
  if (!out->makeCurrent()) {
    fail(why, backend, "eglMakeCurrent");
    return nullptr;  // ~EglContext releases ctx and surf
  }
  return out;
}

}  // namespace blvd::render::egl
