// EGL device backend: enumerates EGL devices (EGL_EXT_device_enumeration) and
// opens one through EGL_EXT_platform_device. It names the GPU explicitly,
// whereas the surfaceless platform goes to whichever EGL vendor answers
// first, so hardware devices are tried before Mesa's software device.

#include "render/egl_common.h"

namespace blvd::render {

namespace {

// Mesa tags its llvmpipe device with EGL_MESA_device_software.
bool isSoftware(PFNEGLQUERYDEVICESTRINGEXTPROC query_string, EGLDeviceEXT dev) {
  if (!query_string) return false;
  return egl::hasExtension(query_string(dev, EGL_EXTENSIONS), "EGL_MESA_device_software");
}

}  // namespace

std::unique_ptr<Context> createEglDeviceContext(std::string& why, bool hardware_only) {
  if (std::string e; !loadEgl(e)) {
    why += "egl-device: " + e;
    return nullptr;
  }
  constexpr const char* kName = "egl-device";
  const char* client = eglApi().QueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  // NVIDIA's EGL advertises EGL_EXT_device_base, the older umbrella for
  // enumeration + query, instead of EGL_EXT_device_enumeration.
  const bool enumeration = egl::hasExtension(client, "EGL_EXT_device_enumeration") ||
                           egl::hasExtension(client, "EGL_EXT_device_base");
  if (!enumeration || !egl::hasExtension(client, "EGL_EXT_platform_device")) {
    why += kName;
    why += ": EGL_EXT_device_enumeration / EGL_EXT_platform_device not offered by this EGL\n";
    return nullptr;
  }
  auto query_devices =
      reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglApi().GetProcAddress("eglQueryDevicesEXT"));
  auto query_string = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
      eglApi().GetProcAddress("eglQueryDeviceStringEXT"));
  auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglApi().GetProcAddress("eglGetPlatformDisplayEXT"));
  if (!query_devices || !get_display) {
    why += kName;
    why += ": eglQueryDevicesEXT or eglGetPlatformDisplayEXT missing\n";
    return nullptr;
  }
  constexpr EGLint kMaxDevices = 16;
  EGLDeviceEXT devices[kMaxDevices];
  EGLint count = 0;
  if (query_devices(kMaxDevices, devices, &count) != EGL_TRUE) {
    egl::fail(why, kName, "eglQueryDevicesEXT");
    return nullptr;
  }
  // Two passes: hardware devices first, then (unless excluded) software ones.
  std::string tried;
  for (int pass = 0; pass < (hardware_only ? 1 : 2); ++pass) {
    for (EGLint i = 0; i < count; ++i) {
      if (isSoftware(query_string, devices[i]) != (pass == 1)) continue;
      EGLDisplay dpy = get_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
      EGLint major = 0, minor = 0;
      if (dpy == EGL_NO_DISPLAY) {
        egl::fail(tried, kName, "eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT)");
        continue;
      }
      if (eglApi().Initialize(dpy, &major, &minor) != EGL_TRUE) {
        egl::fail(tried, kName, "eglInitialize");
        continue;
      }
      if (auto ctx = egl::createOnDisplay(dpy, kName, tried)) return ctx;
    }
  }
  if (tried.empty()) {
    why += kName;
    why += hardware_only ? ": no hardware EGL device\n" : ": no EGL device\n";
  } else {
    why += tried;
  }
  return nullptr;
}

}  // namespace blvd::render
