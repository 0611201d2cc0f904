// EGL surfaceless backend: Mesa's EGL_MESA_platform_surfaceless needs no X,
// no Wayland and no device node, so it is the first choice for headless runs
// (on a machine without a GPU it is llvmpipe).
#include "render/egl_common.h"

namespace blvd::render {

std::unique_ptr<Context> createEglSurfacelessContext(std::string& why) {
  if (std::string e; !loadEgl(e)) {
    why += "egl-surfaceless: " + e;
    return nullptr;
  }
  constexpr const char* kName = "egl-surfaceless";
  const char* client = eglApi().QueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (!egl::hasExtension(client, "EGL_MESA_platform_surfaceless")) {
    why += kName;
    why += ": EGL_MESA_platform_surfaceless not offered by this EGL\n";
    return nullptr;
  }
  auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglApi().GetProcAddress("eglGetPlatformDisplayEXT"));
  if (!get_display) {
    why += kName;
    why += ": eglGetPlatformDisplayEXT missing\n";
    return nullptr;
  }
  EGLDisplay dpy = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  if (dpy == EGL_NO_DISPLAY) {
    egl::fail(why, kName, "eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA)");
    return nullptr;
  }
  EGLint major = 0, minor = 0;
  if (eglApi().Initialize(dpy, &major, &minor) != EGL_TRUE) {
    egl::fail(why, kName, "eglInitialize");
    return nullptr;
  }
  return egl::createOnDisplay(dpy, kName, why);
}

}  // namespace blvd::render
