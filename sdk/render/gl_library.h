// libEGL and libOSMesa, opened at run time (dlopen) rather than linked: a
// process that only tracks, or a head unit whose image has EGL but no
// OSMesa, loads libblvd without them, and a GL driver (Mesa's llvmpipe pulls
// in LLVM) is only mapped when a runtime creates its context. Each table is
// loaded once, thread-safe; a missing library or entry point is named in the
// reason a backend gives for failing. This header has EGL's table (OSMesa's
// is in osmesa_context.cpp: <GL/osmesa.h> clashes with GLES). Internal to sdk/render.
#pragma once
#ifndef EGL_NO_X11
#define EGL_NO_X11  // no Xlib: its macros (None, Status, Bool) break C++ code
#endif
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <cstddef>
#include <mutex>
#include <string>

namespace blvd::render {

struct EglApi {
  PFNEGLGETERRORPROC GetError;
  PFNEGLGETPROCADDRESSPROC GetProcAddress;
  PFNEGLQUERYSTRINGPROC QueryString;
  PFNEGLINITIALIZEPROC Initialize;
  PFNEGLBINDAPIPROC BindAPI;
  PFNEGLCHOOSECONFIGPROC ChooseConfig;
  PFNEGLCREATECONTEXTPROC CreateContext;
  PFNEGLDESTROYCONTEXTPROC DestroyContext;
  PFNEGLCREATEPBUFFERSURFACEPROC CreatePbufferSurface;
  PFNEGLDESTROYSURFACEPROC DestroySurface;
  PFNEGLMAKECURRENTPROC MakeCurrent;
  PFNEGLGETCURRENTCONTEXTPROC GetCurrentContext;
  PFNEGLGETCURRENTDISPLAYPROC GetCurrentDisplay;
  PFNEGLQUERYCONTEXTPROC QueryContext;
};


// The table, or null with "<library>: <why>\n" appended to `why`.
const EglApi* loadEgl(std::string& why);
// The table once loadEgl has succeeded (EGL contexts exist only then).
const EglApi& eglApi();

// A table of a library's entry points, opened once on first use (thread-safe):
// `names` (null-terminated) are tried in turn, `symbols[i]` fills entry i.
// True when every entry point is there; else false, with "<library>: <why>\n"
// appended to `why` (the same reason on every later call).
struct LibraryTable {
  const char* const* names;
  const char* const* symbols;
  void** fns;
  size_t n;
  std::once_flag once{};
  bool ok = false;
  std::string err{};
};
bool openOnce(LibraryTable& table, std::string& why);

}  // namespace blvd::render
