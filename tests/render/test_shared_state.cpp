// Shared mode: the host owns an EGL context and a framebuffer, sets odd GL
// state, and blvd must leave every piece of state it touches as it found it,
// while still drawing into the host's framebuffer.
#define EGL_NO_X11
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <gtest/gtest.h>

#include <utility>
#include <vector>

#include "render/context.h"
#include "render/gl_api.h"
#include "render/prepared_mesh.h"
#include "render/renderer.h"
#include "scene.h"

namespace blvd::render {
namespace {

constexpr int kW = 96, kH = 64;

// The host side: its own surfaceless EGL display and GLES context.
class HostContext {
 public:
  bool create(std::string& why) {
    auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
        eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (!get_display) return (why = "no eglGetPlatformDisplayEXT", false);
    dpy_ = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    EGLint major = 0, minor = 0;
    if (dpy_ == EGL_NO_DISPLAY || !eglInitialize(dpy_, &major, &minor)) {
      return (why = "host: no surfaceless display", false);
    }
    eglBindAPI(EGL_OPENGL_ES_API);
    const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_NONE};
    ctx_ = eglCreateContext(dpy_, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attribs);
    if (ctx_ == EGL_NO_CONTEXT) return (why = "host: eglCreateContext failed", false);
    if (!eglMakeCurrent(dpy_, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx_)) {
      return (why = "host: eglMakeCurrent failed", false);
    }
    return true;
  }
  ~HostContext() {
    if (ctx_ != EGL_NO_CONTEXT) {
      eglMakeCurrent(dpy_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
      eglDestroyContext(dpy_, ctx_);
    }
  }

 private:
  EGLDisplay dpy_ = EGL_NO_DISPLAY;
  EGLContext ctx_ = EGL_NO_CONTEXT;
};

// Every state value the renderer could disturb, as glGetIntegerv sees it.
const std::vector<std::pair<GLenum, int>> kWatched = {
    {GL_CURRENT_PROGRAM, 1},
    {GL_VERTEX_ARRAY_BINDING, 1},
    {GL_ARRAY_BUFFER_BINDING, 1},
    {GL_ELEMENT_ARRAY_BUFFER_BINDING, 1},
    {GL_PIXEL_PACK_BUFFER_BINDING, 1},
    {GL_COPY_READ_BUFFER_BINDING, 1},
    {GL_COPY_WRITE_BUFFER_BINDING, 1},
    {GL_DRAW_FRAMEBUFFER_BINDING, 1},
    {GL_READ_FRAMEBUFFER_BINDING, 1},
    {GL_RENDERBUFFER_BINDING, 1},
    {GL_VIEWPORT, 4},
    {GL_ACTIVE_TEXTURE, 1},
    {GL_DEPTH_TEST, 1},
    {GL_DEPTH_FUNC, 1},
    {GL_DEPTH_WRITEMASK, 1},
    {GL_DEPTH_RANGE, 2},
    {GL_CULL_FACE, 1},
    {GL_CULL_FACE_MODE, 1},
    {GL_FRONT_FACE, 1},
    {GL_BLEND, 1},
    {GL_POLYGON_OFFSET_FILL, 1},
    {GL_POLYGON_OFFSET_FACTOR, 1},
    {GL_POLYGON_OFFSET_UNITS, 1},
    {GL_SCISSOR_TEST, 1},
    {GL_SCISSOR_BOX, 4},
    {GL_STENCIL_TEST, 1},
    {GL_COLOR_WRITEMASK, 4},
    {GL_PACK_ALIGNMENT, 1},
    {GL_PACK_ROW_LENGTH, 1},
    {GL_COLOR_CLEAR_VALUE, 4},
};

std::vector<GLint> snapshot(const GlApi& gl) {
  std::vector<GLint> out;
  for (const auto& [e, n] : kWatched) {
    GLint v[4] = {0, 0, 0, 0};
    gl.GetIntegerv(e, v);
    out.insert(out.end(), v, v + n);
  }
  return out;
}

void expectSame(const std::vector<GLint>& before, const std::vector<GLint>& after,
                const char* step) {
  ASSERT_EQ(before.size(), after.size());
  size_t k = 0;
  for (const auto& [e, n] : kWatched) {
    for (int i = 0; i < n; ++i, ++k) {
      EXPECT_EQ(before[k], after[k]) << "after " << step << ": state 0x" << std::hex << e
                                     << "[" << std::dec << i << "] changed";
    }
  }
}

GLuint hostProgram(const GlApi& gl) {
  const char* vs = "#version 300 es\nvoid main() { gl_Position = vec4(0.0); }\n";
  const char* fs =
      "#version 300 es\nprecision mediump float;\nout vec4 c;\nvoid main() { c = vec4(1.0); }\n";
  GLuint p = gl.CreateProgram();
  for (auto [type, src] : {std::pair{GLenum{GL_VERTEX_SHADER}, vs}, std::pair{GLenum{GL_FRAGMENT_SHADER}, fs}}) {
    GLuint s = gl.CreateShader(type);
    gl.ShaderSource(s, 1, &src, nullptr);
    gl.CompileShader(s);
    gl.AttachShader(p, s);
    gl.DeleteShader(s);
  }
  gl.LinkProgram(p);
  return p;
}

TEST(SharedContext, RestoresHostStateAndDrawsIntoHostFramebuffer) {
  HostContext host;
  std::string why;
  ASSERT_TRUE(host.create(why)) << why;
  auto ctx = createContext(Backend::Shared, why);
  ASSERT_NE(ctx, nullptr) << why;
  EXPECT_STREQ(ctx->name(), "shared");
  EXPECT_TRUE(ctx->isShared());
  EXPECT_TRUE(ctx->isGles());
  GlApi gl;
  ASSERT_TRUE(gl.load(*ctx, why)) << why;

  // Host framebuffer, buffers, program and a deliberately odd state.
  GLuint fbo = 0, rb[2] = {0, 0}, vao = 0, buf[5] = {0, 0, 0, 0, 0};
  gl.GenRenderbuffers(2, rb);
  gl.BindRenderbuffer(GL_RENDERBUFFER, rb[0]);
  gl.RenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, kW, kH);
  gl.BindRenderbuffer(GL_RENDERBUFFER, rb[1]);
  gl.RenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, kW, kH);
  gl.GenFramebuffers(1, &fbo);
  gl.BindFramebuffer(GL_FRAMEBUFFER, fbo);
  gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb[0]);
  gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb[1]);
  ASSERT_EQ(gl.CheckFramebufferStatus(GL_FRAMEBUFFER), GLenum{GL_FRAMEBUFFER_COMPLETE});
  gl.ClearColor(1.0f, 0.0f, 1.0f, 1.0f);
  gl.Clear(GL_COLOR_BUFFER_BIT);

  gl.GenVertexArrays(1, &vao);
  gl.BindVertexArray(vao);
  gl.GenBuffers(5, buf);
  gl.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, buf[0]);
  gl.BindBuffer(GL_ARRAY_BUFFER, buf[1]);
  gl.BindBuffer(GL_PIXEL_PACK_BUFFER, buf[2]);
  gl.BindBuffer(GL_COPY_READ_BUFFER, buf[3]);
  gl.BindBuffer(GL_COPY_WRITE_BUFFER, buf[4]);
  gl.BufferData(GL_PIXEL_PACK_BUFFER, 16, nullptr, GL_STREAM_READ);
  const GLuint program = hostProgram(gl);
  gl.UseProgram(program);
  gl.BindRenderbuffer(GL_RENDERBUFFER, rb[1]);
  gl.Viewport(3, 5, 17, 19);
  gl.ActiveTexture(GL_TEXTURE3);
  gl.Disable(GL_DEPTH_TEST);
  gl.DepthFunc(GL_GREATER);
  gl.DepthMask(GL_FALSE);
  gl.DepthRangef(0.1f, 0.9f);
  gl.Enable(GL_CULL_FACE);
  gl.CullFace(GL_FRONT);
  gl.FrontFace(GL_CW);
  gl.Enable(GL_BLEND);
  gl.Enable(GL_POLYGON_OFFSET_FILL);
  gl.PolygonOffset(2.0f, 3.0f);
  gl.Enable(GL_SCISSOR_TEST);
  gl.Scissor(1, 2, 3, 4);
  gl.Enable(GL_STENCIL_TEST);
  gl.ColorMask(GL_TRUE, GL_FALSE, GL_TRUE, GL_FALSE);
  gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
  gl.PixelStorei(GL_PACK_ROW_LENGTH, 7);
  ASSERT_EQ(gl.GetError(), GLenum{GL_NO_ERROR});
  const std::vector<GLint> before = snapshot(gl);

  auto renderer = Renderer::create(*ctx, RendererDesc{}, why);
  ASSERT_NE(renderer, nullptr) << why;
  expectSame(before, snapshot(gl), "create");

  const uint8_t red[4] = {200, 40, 40, 255};
  const MeshHandle box = renderer->upload(test::makeBox(0, 2, -10, 4, 4, 4, red));
  ASSERT_TRUE(renderer->isValid(box)) << renderer->lastError();
  expectSame(before, snapshot(gl), "upload");

  Camera cam;
  cam.eye_enu = {0.0, 0.0, 2.0};
  cam.width = kW;
  cam.height = kH;
  FrameStats stats;
  // With a wall in front of the box drawn behind it (as the terrain is).
  const uint8_t green[4] = {40, 200, 40, 255};
  const MeshHandle list[2] = {box, renderer->upload(test::makeBox(0, 2, -5.5f, 6, 1.4f, 1, green))};
  RenderOptions behind;
  behind.behind_from = 1;
  ASSERT_TRUE(renderer->render(cam, list, 2, &stats, behind)) << renderer->lastError();
  EXPECT_EQ(stats.meshes_drawn, 2u);
  expectSame(before, snapshot(gl), "render");

  std::vector<uint8_t> img(static_cast<size_t>(kW) * kH * 4);
  ASSERT_TRUE(renderer->readPixels(img.data())) << renderer->lastError();
  expectSame(before, snapshot(gl), "readPixels");

  // The frame landed in the host's framebuffer, over the host's magenta
  // clear, in spite of the host's colour mask and scissor.
  const test::Rgb sky = test::pixel(img, kW, kW / 2, 0);
  EXPECT_GT(sky.b, sky.r + 30) << sky.r << "," << sky.g << "," << sky.b;
  EXPECT_GT(sky.g, 100);
  const test::Rgb mid = test::pixel(img, kW, kW / 2, kH / 2);
  EXPECT_GT(mid.r, 150) << mid.r << "," << mid.g << "," << mid.b;
  EXPECT_LT(mid.g, 90);

  // A slab upload and a GPU-side copy into another slab (a block two cells share).
  const geo::MeshData boxMesh = test::makeBox(0, 2, -10, 4, 4, 4, red);
  std::vector<uint8_t> staging(preparedBytes(boxMesh.vertexCount(), boxMesh.indices.size(), 0, 0));
  StagingArena arena{staging.data(), staging.size(), 0};
  PreparedMesh prepared;
  ASSERT_TRUE(prepareMesh(boxMesh, arena, prepared, why)) << why;
  SlabDesc sd;
  sd.vertex_bytes = prepared.vertexBytes();
  sd.index_bytes = prepared.indexBytes() + 3;
  sd.meshes = 1;
  const SlabHandle from = renderer->createSlab(sd), to = renderer->createSlab(sd);
  const MeshHandle placed = renderer->uploadToSlab(from, prepared);
  ASSERT_TRUE(renderer->isValid(placed)) << renderer->lastError();
  expectSame(before, snapshot(gl), "slab upload");
  SlabUpload up;
  ASSERT_TRUE(renderer->beginSlabCopy(to, placed, up)) << renderer->lastError();
  bool finished = false;
  EXPECT_TRUE(renderer->isValid(renderer->continueSlabUpload(up, 1 << 20, finished))) << renderer->lastError();
  EXPECT_TRUE(finished);
  expectSame(before, snapshot(gl), "slab copy");

  renderer->release(box);
  renderer->release(list[1]);
  expectSame(before, snapshot(gl), "release");
  renderer.reset();
  expectSame(before, snapshot(gl), "destroy");
  EXPECT_EQ(gl.GetError(), GLenum{GL_NO_ERROR});
  ctx.reset();  // must not destroy the host context
  GLint still = 0;
  gl.GetIntegerv(GL_CURRENT_PROGRAM, &still);
  EXPECT_EQ(static_cast<GLuint>(still), program);
}

}  // namespace
}  // namespace blvd::render
