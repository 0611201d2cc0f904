// EGL plumbing shared by the two EGL backends (surfaceless and device) and the
// Shared backend: error names, extension checks, and context creation on an
// already initialised display. Internal to sdk/render.
#pragma once
#include "render/gl_library.h"

#include <memory>
#include <string>

#include "render/context.h"

namespace blvd::render::egl {

// "EGL_BAD_ALLOC" etc.; static storage.
const char* errorName(EGLint code);

// Whole-word search in a space-separated extension string (nullptr-safe).
bool hasExtension(const char* extensions, const char* name);

// Creates a GLES 3.x context on `dpy` (initialised by the caller) and makes it
// current, surfaceless when EGL_KHR_surfaceless_context allows, else on a tiny
// pbuffer. `backend` is the backendName() reported by the context and used as
// the prefix of the reason appended to `why` on failure.
std::unique_ptr<Context> createOnDisplay(EGLDisplay dpy, const char* backend, std::string& why);

// Appends "<backend>: <what> failed (<eglGetError name>)\n" to why.
void fail(std::string& why, const char* backend, const char* what);

}  // namespace blvd::render::egl
