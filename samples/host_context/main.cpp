// host_context: a host that owns its GL context and framebuffer and lets blvd
// draw the street view into it between two passes of its own.
//
// 1. The host creates a surfaceless EGL display, a GLES 3 context and an
//    offscreen framebuffer (a window system's surface works the same way).
// 2. Before blvd: it clears to its own colour and sets odd GL state of its
//    own (program, buffers, viewport, scissor, blend, ...), as a real HUD
//    renderer would leave it.
// 3. blvd renders with BLVD_CONTEXT_SHARED into the framebuffer the host has
//    bound, and must restore every piece of state it touched: the sample
//    compares glGet before and after and fails if anything moved.
// 4. After blvd: the host draws a route line and a HUD bar over the frame.
// 5. It writes the frame as PNG and checks that all three layers are there.
//
// Usage: host_context PACKAGE.blvd --lat LAT --lon LON --heading DEG -o frame.png
#define EGL_NO_X11
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GLES3/gl3.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "blvd/blvd.h"
#include "common/png.h"

namespace {

constexpr int kW = 640, kH = 384;

int fail(const char* what) {
  std::fprintf(stderr, "host_context: %s\n", what);
  return 1;
}

// The state a host's own renderer cares about, as glGetIntegerv reports it.
const std::vector<std::pair<GLenum, int>> kWatched = {
    {GL_CURRENT_PROGRAM, 1},  {GL_VERTEX_ARRAY_BINDING, 1}, {GL_ARRAY_BUFFER_BINDING, 1},
    {GL_DRAW_FRAMEBUFFER_BINDING, 1}, {GL_READ_FRAMEBUFFER_BINDING, 1}, {GL_RENDERBUFFER_BINDING, 1},
    {GL_VIEWPORT, 4},         {GL_SCISSOR_BOX, 4},          {GL_SCISSOR_TEST, 1},
    {GL_BLEND, 1},            {GL_DEPTH_TEST, 1},           {GL_DEPTH_FUNC, 1},
    {GL_DEPTH_WRITEMASK, 1},  {GL_CULL_FACE, 1},            {GL_CULL_FACE_MODE, 1},
    {GL_FRONT_FACE, 1},       {GL_ACTIVE_TEXTURE, 1},       {GL_TEXTURE_BINDING_2D, 1},
    {GL_COLOR_WRITEMASK, 4},  {GL_UNPACK_ALIGNMENT, 1},     {GL_PACK_ALIGNMENT, 1},
    {GL_STENCIL_TEST, 1},     {GL_POLYGON_OFFSET_FILL, 1},
};

std::vector<GLint> snapshot() {
  std::vector<GLint> v;
  for (const auto& [name, n] : kWatched) {
    GLint buf[4] = {0, 0, 0, 0};
    glGetIntegerv(name, buf);
    v.insert(v.end(), buf, buf + n);
  }
  return v;
}

GLuint shader(GLenum type, const char* src) {
  const GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  return s;
}

// The host's flat-colour 2D program: positions in clip space.
GLuint flatProgram() {
  const GLuint p = glCreateProgram();
  glAttachShader(p, shader(GL_VERTEX_SHADER, "#version 300 es\nlayout(location=0) in vec2 p;\n"
                                              "void main(){gl_Position=vec4(p,0.0,1.0);}\n"));
  glAttachShader(p, shader(GL_FRAGMENT_SHADER, "#version 300 es\nprecision mediump float;\nuniform vec4 c;\n"
                                                "out vec4 o;\nvoid main(){o=c;}\n"));
  glLinkProgram(p);
  return p;
}

void drawFlat(GLuint program, GLuint vbo, const std::vector<float>& xy, GLenum mode, const float rgba[4]) {
  glUseProgram(program);
  glUniform4fv(glGetUniformLocation(program, "c"), 1, rgba);
  glBindBuffer(GL_ARRAY_BUFFER, vbo);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(xy.size() * sizeof(float)), xy.data(), GL_STREAM_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 0, nullptr);
  glDrawArrays(mode, 0, GLsizei(xy.size() / 2));
}

}  // namespace

int main(int argc, char** argv) {
  std::string package, out = "host_context.png";
  double lat = 43.735370, lon = 7.417288, heading = 211;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : ""; };
    if (a == "--lat") lat = std::atof(next());
    else if (a == "--lon") lon = std::atof(next());
    else if (a == "--heading") heading = std::atof(next());
    else if (a == "-o") out = next();
    else if (a[0] != '-') package = a;
    else return fail(("unknown option " + a).c_str());
  }
  if (package.empty()) return fail("usage: host_context PACKAGE.blvd [--lat --lon --heading] [-o frame.png]");

  // 1. The host's display, context and framebuffer.
  auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (!get_display) return fail("no eglGetPlatformDisplayEXT");
  EGLDisplay dpy = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  EGLint major = 0, minor = 0;
  if (dpy == EGL_NO_DISPLAY || !eglInitialize(dpy, &major, &minor)) return fail("no surfaceless EGL display");
  eglBindAPI(EGL_OPENGL_ES_API);
  const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_NONE};
  EGLContext ctx = eglCreateContext(dpy, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attribs);
  if (ctx == EGL_NO_CONTEXT || !eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx))
    return fail("cannot create and bind a GLES 3 context");
  GLuint fbo = 0, rb[2] = {0, 0}, vao = 0, vbo = 0;
  glGenRenderbuffers(2, rb);
  glBindRenderbuffer(GL_RENDERBUFFER, rb[0]);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, kW, kH);
  glBindRenderbuffer(GL_RENDERBUFFER, rb[1]);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, kW, kH);
  glGenFramebuffers(1, &fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb[0]);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb[1]);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) return fail("framebuffer incomplete");
  glGenVertexArrays(1, &vao);
  glBindVertexArray(vao);
  glGenBuffers(1, &vbo);
  const GLuint flat = flatProgram();

  // 2. The host's pass before blvd, leaving its own state behind.
  glViewport(0, 0, kW, kH);
  glClearColor(1.0f, 0.0f, 1.0f, 1.0f);  // magenta: must not survive where blvd draws
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glEnable(GL_SCISSOR_TEST);
  glScissor(0, 0, kW, kH);
  glUseProgram(flat);
  glBindBuffer(GL_ARRAY_BUFFER, vbo);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);

  // 3. blvd into the host's framebuffer.
  blvd_runtime_desc desc{};
  desc.struct_size = sizeof desc;
  desc.package_path = package.c_str();
  desc.width = kW;
  desc.height = kH;
  desc.backend = BLVD_CONTEXT_SHARED;
  blvd_runtime* rt = nullptr;
  if (blvd_runtime_create(&desc, &rt) != BLVD_OK) return fail(blvd_last_error(nullptr));
  if (blvd_set_pose_geo(rt, lat, lon, float(heading), 0.f) != BLVD_OK || blvd_wait_resident(rt, 30000) != BLVD_OK)
    return fail(blvd_last_error(rt));
  const std::vector<GLint> before = snapshot();
  blvd_frame_stats fs{};
  fs.struct_size = sizeof fs;
  if (blvd_render(rt, &fs) != BLVD_OK) return fail(blvd_last_error(rt));
  const std::vector<GLint> after = snapshot();
  int moved = 0;
  for (size_t i = 0, k = 0; i < kWatched.size(); k += size_t(kWatched[i].second), ++i)
    for (int j = 0; j < kWatched[i].second; ++j)
      if (before[k + size_t(j)] != after[k + size_t(j)]) {
        std::fprintf(stderr, "host_context: GL state 0x%04x[%d] was %d before blvd_render, %d after\n",
                     kWatched[i].first, j, before[k + size_t(j)], after[k + size_t(j)]);
        ++moved;
      }
  if (moved) return fail("blvd_render did not restore the host's GL state");

  // 4. The host's pass after blvd: a route line and a HUD bar.
  const float route_rgba[4] = {0.1f, 0.6f, 1.0f, 0.9f}, hud_rgba[4] = {0.0f, 0.0f, 0.0f, 0.6f};
  drawFlat(flat, vbo, {-0.05f, -1.0f, 0.05f, -1.0f, -0.01f, -0.3f, 0.01f, -0.3f}, GL_TRIANGLE_STRIP, route_rgba);
  drawFlat(flat, vbo, {-1.0f, 0.85f, 1.0f, 0.85f, -1.0f, 1.0f, 1.0f, 1.0f}, GL_TRIANGLE_STRIP, hud_rgba);

  // 5. The frame, and a check that all three layers are in it.
  std::vector<uint8_t> px(size_t(kW) * kH * 4);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glReadPixels(0, 0, kW, kH, GL_RGBA, GL_UNSIGNED_BYTE, px.data());
  auto at = [&](int x, int y_from_top) { return &px[(size_t(kH - 1 - y_from_top) * kW + size_t(x)) * 4]; };
  size_t magenta = 0;
  for (int y = kH / 4; y < kH; ++y)  // below the HUD bar
    for (int x = 0; x < kW; ++x) {
      const uint8_t* p = at(x, y);
      magenta += p[0] > 240 && p[1] < 15 && p[2] > 240;
    }
  const uint8_t* hud = at(kW / 2, 5);
  const uint8_t* line = at(kW / 2, kH - 10);
  const bool hud_ok = hud[0] < 140 && hud[1] < 140 && hud[2] < 140;
  const bool line_ok = line[2] > line[0] + 60;
  std::vector<uint8_t> flipped(px.size());
  for (int y = 0; y < kH; ++y) std::memcpy(&flipped[size_t(y) * kW * 4], at(0, y), size_t(kW) * 4);
  if (!samples::writePng(out, flipped.data(), kW, kH)) return fail(("cannot write " + out).c_str());
  std::printf("wrote %s: blvd drew %llu triangles (cell %u) between the host's passes; GL state restored "
              "(%zu values checked); HUD %s, route line %s, host clear colour left in %zu pixels\n",
              out.c_str(), static_cast<unsigned long long>(fs.triangles), fs.cell, after.size(), hud_ok ? "ok" : "MISSING",
              line_ok ? "ok" : "MISSING", magenta);
  blvd_runtime_destroy(rt);
  eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(dpy, ctx);
  eglTerminate(dpy);
  return hud_ok && line_ok && magenta == 0 && fs.triangles > 0 ? 0 : 1;
}
