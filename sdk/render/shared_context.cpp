// Shared backend: adopts the EGL context the host made current on this thread.
// blvd never makes it current, never releases it and never destroys it; the
// renderer restores the GL state it touches (see gl_state.h).
#include "render/egl_common.h"

namespace blvd::render {

namespace {

class SharedContext final : public Context {
 public:
  SharedContext(EGLContext ctx, bool gles) : ctx_(ctx), gles_(gles) {}
  ~SharedContext() override = default;  // the host owns the context

  // The host may switch contexts between frames; drawing into someone else's
  // context would corrupt it, so this only checks.
  bool makeCurrent() override { return eglApi().GetCurrentContext() == ctx_; }
  const char* name() const override { return "shared"; }
  void* getProcAddress(const char* fn) override {
    return reinterpret_cast<void*>(eglApi().GetProcAddress(fn));
  }
  bool isGles() const override { return gles_; }
  bool isShared() const override { return true; }

 private:
  EGLContext ctx_;
  bool gles_;
};

}  // namespace

std::unique_ptr<Context> createSharedContext(std::string& why) {
  if (std::string e; !loadEgl(e)) {
    why += "shared: " + e;
    return nullptr;
  }
  EGLContext ctx = eglApi().GetCurrentContext();
  if (ctx == EGL_NO_CONTEXT) {
    why += "shared: no EGL context is current on the calling thread\n";
    return nullptr;
  }
  EGLint client_type = EGL_OPENGL_ES_API;
  eglApi().QueryContext(eglApi().GetCurrentDisplay(), ctx, EGL_CONTEXT_CLIENT_TYPE, &client_type);
  return std::make_unique<SharedContext>(ctx, client_type == EGL_OPENGL_ES_API);
}

}  // namespace blvd::render
