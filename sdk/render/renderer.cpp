// Renderer: GL resources, the mesh pool, and the frame.
//
// Frame order: the culled meshes front to back (so llvmpipe's early depth
// test rejects hidden fragments), then the background (sky + ground) only
// where the depth is still 1.0. The ground is part of the background
// pass rather than a big quad: a quad at y = 0 would z-fight with street
// ribbons a few centimetres above it at every distance beyond ~100 m with a
// 24-bit depth buffer, and polygon offset cannot fix that at the grazing
// angles of a street-level view. Drawn as background it can never cover
// anything (city geometry is at y >= 0 and the eye above it).
#include "render/renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <deque>

#include "render/atlas_etc2.h"
#include "render/context.h"
#include "render/etc2.h"
#include "render/frustum.h"
#include "render/gl_api.h"
#include "render/gl_state.h"
#include "render/shaders.h"

#include <stb_image.h>

namespace blvd::render {

namespace {

constexpr uint32_t kIndexBits = 20;
constexpr uint32_t kIndexMask = (1u << kIndexBits) - 1;
constexpr uint32_t kGenerationMask = (1u << (32 - kIndexBits)) - 1;

// Texels repeated past an image's right and bottom edges in its place in a
// slab's atlas level: the place (tw x th at that level, the image's size
// rounded up to the atlas grid) holds a smaller image in its corner, the rest
// is what earlier cells' images left there. The shader maps the image by one
// scale for every level (w / W of level 0), but a level of the image is
// floor(w / 2^l) texels wide, so linear filtering of a level reads up to two
// texels past the texels written. Repeating the edge makes those texels the
// image's own (the clamp-to-edge rule an image of its own would get) and the
// frame independent of what the slab held before (SlotHistory.* test).
constexpr int kEdgePad = 2;

void padLevel(const GlApi& gl, int level, const uint8_t* texels, int x0, int y0, int w, int h, int tw, int th) {
  const int x_end = std::min(w + kEdgePad, tw), y_end = std::min(h + kEdgePad, th);
  const uint8_t* last_column = texels + uint64_t(w - 1) * 4;
  const uint8_t* last_row = texels + uint64_t(h - 1) * uint64_t(w) * 4;
  gl.PixelStorei(GL_UNPACK_ROW_LENGTH, w);  // one texel of each row
  for (int x = w; x < x_end; ++x)
    gl.TexSubImage2D(GL_TEXTURE_2D, level, x0 + x, y0, 1, h, GL_RGBA, GL_UNSIGNED_BYTE, last_column);
  gl.PixelStorei(GL_UNPACK_ROW_LENGTH, 0);
  for (int y = h; y < y_end; ++y) {
    gl.TexSubImage2D(GL_TEXTURE_2D, level, x0, y0 + y, w, 1, GL_RGBA, GL_UNSIGNED_BYTE, last_row);
    for (int x = w; x < x_end; ++x)
      gl.TexSubImage2D(GL_TEXTURE_2D, level, x0 + x, y0 + y, 1, 1, GL_RGBA, GL_UNSIGNED_BYTE,
                       last_row + uint64_t(w - 1) * 4);
  }
}

// The slab's atlas bound for an upload; in a host's context, with nothing of
// the host's unpack state (a bound unpack buffer, a row length) redirecting it.
void bindAtlasForUpload(const GlApi& gl, GLuint texture, bool shared) {
  gl.ActiveTexture(GL_TEXTURE0);
  gl.BindTexture(GL_TEXTURE_2D, texture);
  if (shared) {
    gl.BindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
    gl.PixelStorei(GL_UNPACK_ROW_LENGTH, 0);
  }
}

// The image's level that fills atlas level l of its place: its own, or past
// the end of its chain its last (1 x 1), which is all a place that small
// shows.
const uint8_t* atlasSource(const PreparedMesh& p, int l, int& w, int& h) {
  return mipLevel(p, std::min(l, p.mip_levels - 1), w, h);
}

// Bytes an image's levels copy into an atlas (kAtlasLevels of them).
uint64_t atlasUploadBytes(const PreparedMesh& p) {
  uint64_t n = 0;
  for (int l = 0; l < kAtlasLevels; ++l) {
    int w = 0, h = 0;
    atlasSource(p, l, w, h);
    n += uint64_t(w) * uint64_t(h) * 4;
  }
  return n;
}

void setTextureSampling(const GlApi& gl) {
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
}

struct MeshSlot {
  GLuint vao = 0, vbo = 0, ibo = 0;
  GLuint texture = 0;  // impostors: the captured colour
  GLsizei index_count = 0;
  GLenum index_type = GL_UNSIGNED_SHORT;
  uint64_t index_offset = 0;  // bytes into ibo (slab meshes share one)
  uint64_t vertex_offset = 0; // bytes into vbo
  uint32_t vertex_count = 0;
  uint32_t slab = 0;          // slab index + 1, or 0: the mesh owns its GL objects
  float uv_scale[2] = {1, 1}; // image size over the slab atlas's size
  float uv_offset[2] = {0, 0}; // the image's place in the atlas, in atlas units
  uint32_t generation = 1;
  bool live = false;
  glm::dvec3 center{0.0};  // glTF axes, package frame
  glm::dvec3 half{0.0};
  uint64_t bytes = 0;
  MeshPart parts[kMaxMeshParts];  // culled one by one when there are two or more
  int part_count = 0;
  bool lines = false;             // GL_LINES, not GL_TRIANGLES
};

// Uniform locations of one program (-1 when the program does not use one).
struct Uniforms {
  GLint sun_dir = -1, sun_color = -1, sky_ambient = -1, ground_ambient = -1, horizon = -1,
        inv_fog2 = -1;
  GLint ray_basis = -1, zenith = -1, ground = -1, eye_height = -1;  // background
  GLint viewproj = -1, offset = -1;                                 // meshes
  GLint item = -1, forward = -1, depth_scale = -1, texture = -1, uv_scale = -1, uv_offset = -1;  // capture, impostors
  GLint uv_clamp = -1;                                                            // upscale
};

glm::vec3 srgbToLinear(const float c[3]) {
  return {std::pow(c[0], 2.2f), std::pow(c[1], 2.2f), std::pow(c[2], 2.2f)};
}

const void* byteOffset(size_t n) { return reinterpret_cast<const void*>(n); }

}  // namespace

struct Renderer::Slab {
  SlabDesc desc;
  GLuint vbo = 0, ibo = 0, atlas = 0;
  std::vector<GLuint> vaos;            // made once, handed out in order
  std::vector<uint32_t> meshes;        // slot indices placed here, reserved for desc.meshes
  struct Place {
    int x, y, w, h;  // rounded to the atlas grid
  };
  std::vector<Place> places;  // the images' places in the atlas, reserved for desc.meshes
  uint64_t vertex_used = 0, index_used = 0, texture_used = 0;
  uint32_t vaos_used = 0;
  uint32_t resets = 0;  // abandons the SlabUploads begun before
};

struct Renderer::Impl {
  GLuint bg_program = 0, mesh_program = 0;
  GLuint item_program = 0, cap_color_program = 0, cap_depth_program = 0, tex_program = 0, up_program = 0;
  Uniforms bg, mesh, item, cap_color, cap_depth, tex, up;
  GLuint empty_vao = 0;  // core profile needs a VAO even for attribute-less draws
  GLuint fbo = 0, color_rb = 0, depth_rb = 0;
  GLuint scaled_fbo = 0, scaled_color_tex = 0, scaled_depth_rb = 0;  // RendererDesc::scaled_target
  int scaled_w = 0, scaled_h = 0;
  GLint host_fbo = 0;  // shared: framebuffer bound during the last render()

  std::vector<MeshSlot> slots;  // grows up to capacity, reserved once
  std::vector<uint32_t> free_slots;
  uint32_t capacity = 0;

  // render() scratch: visible list entries with their distance, reserved at
  // init so a frame does not allocate.
  std::vector<std::pair<float, uint32_t>> order;

  // upload() scratch, kept to avoid reallocating for every mesh.
  std::vector<uint8_t> scratch;
  std::deque<Slab> slabs;  // fixed GPU arenas, made at create

  // Look, derived once per setLook().
  glm::vec3 sun_dir{0.0f, 1.0f, 0.0f}, sun_color{0.0f}, sky_ambient{0.0f}, ground_ambient{0.0f};
  glm::vec3 zenith{0.0f}, horizon{0.0f}, ground{0.0f};
};

RendererDesc rendererDescDefaults(const RendererDesc& desc) {
  RendererDesc d = desc;
  if (d.width == 0) d.width = 800;
  if (d.height == 0) d.height = 480;
  if (d.mesh_capacity == 0) d.mesh_capacity = 16384;
  return d;
}

Renderer::Renderer(Context& ctx) : ctx_(ctx), gl_(new GlApi), impl_(new Impl) {}

bool Renderer::fail(const char* what) {
  error_ = what;
  return false;
}

bool Renderer::outOfMemory() const { return out_of_memory_; }

namespace {
constexpr GLenum kContextLost = 0x0507;  // GL_CONTEXT_LOST (GLES 3.2, KHR_robustness)
constexpr char kLostMessage[] =
    "GL context lost (0x0507: the GPU was reset): its objects are gone; destroy the runtime and create it again";
}  // namespace

bool Renderer::lost() {
  if (context_lost_) error_ = kLostMessage;
  return context_lost_;
}

const char* Renderer::backendName() const { return ctx_.name(); }

namespace {

GLuint compile(const GlApi& gl, GLenum type, bool gles, const char* body, std::string& err) {
  const GLuint s = gl.CreateShader(type);
  const char* parts[3] = {gles ? shaders::kVersionEs : shaders::kVersionCore, shaders::kPrelude,
                          body};
  gl.ShaderSource(s, 3, parts, nullptr);
  gl.CompileShader(s);
  GLint ok = GL_FALSE;
  gl.GetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (ok != GL_TRUE) {
    char log[2048] = {0};
    gl.GetShaderInfoLog(s, sizeof log, nullptr, log);
    err = std::string(type == GL_VERTEX_SHADER ? "vertex" : "fragment") +
          " shader does not compile: " + log;
    gl.DeleteShader(s);
    return 0;
  }
  return s;
}

GLuint link(const GlApi& gl, bool gles, const char* vs_body, const char* fs_body,
            std::string& err) {
  const GLuint vs = compile(gl, GL_VERTEX_SHADER, gles, vs_body, err);
  if (!vs) return 0;
  const GLuint fs = compile(gl, GL_FRAGMENT_SHADER, gles, fs_body, err);
  if (!fs) {
    gl.DeleteShader(vs);
    return 0;
  }
  const GLuint p = gl.CreateProgram();
  gl.AttachShader(p, vs);
  gl.AttachShader(p, fs);
  gl.LinkProgram(p);
  // Flagged for deletion; freed with the program.
  gl.DeleteShader(vs);
  gl.DeleteShader(fs);
  GLint ok = GL_FALSE;
  gl.GetProgramiv(p, GL_LINK_STATUS, &ok);
  if (ok != GL_TRUE) {
    char log[2048] = {0};
    gl.GetProgramInfoLog(p, sizeof log, nullptr, log);
    err = std::string("program does not link: ") + log;
    gl.DeleteProgram(p);
    return 0;
  }
  return p;
}

Uniforms locate(const GlApi& gl, GLuint p) {
  Uniforms u;
  u.sun_dir = gl.GetUniformLocation(p, "u_sun_dir");
  u.sun_color = gl.GetUniformLocation(p, "u_sun_color");
  u.sky_ambient = gl.GetUniformLocation(p, "u_sky_ambient");
  u.ground_ambient = gl.GetUniformLocation(p, "u_ground_ambient");
  u.horizon = gl.GetUniformLocation(p, "u_horizon");
  u.inv_fog2 = gl.GetUniformLocation(p, "u_inv_fog2");
  u.ray_basis = gl.GetUniformLocation(p, "u_ray_basis");
  u.zenith = gl.GetUniformLocation(p, "u_zenith");
  u.ground = gl.GetUniformLocation(p, "u_ground");
  u.eye_height = gl.GetUniformLocation(p, "u_eye_height");
  u.viewproj = gl.GetUniformLocation(p, "u_viewproj");
  u.offset = gl.GetUniformLocation(p, "u_offset");
  u.item = gl.GetUniformLocation(p, "u_item");
  u.forward = gl.GetUniformLocation(p, "u_forward");
  u.depth_scale = gl.GetUniformLocation(p, "u_depth_scale");
  u.texture = gl.GetUniformLocation(p, "u_texture");
  u.uv_scale = gl.GetUniformLocation(p, "u_uv_scale");
  u.uv_offset = gl.GetUniformLocation(p, "u_uv_offset");
  u.uv_clamp = gl.GetUniformLocation(p, "u_uv_clamp");
  return u;
}

// "OpenGL ES 3.2 Mesa ..." or "4.5 (Core Profile) Mesa ...".
bool parseVersion(const char* v, bool& gles, int& major, int& minor) {
  if (!v) return false;
  gles = std::strncmp(v, "OpenGL ES", 9) == 0;
  const char* p = v;
  while (*p && (*p < '0' || *p > '9')) ++p;
  return std::sscanf(p, "%d.%d", &major, &minor) == 2;
}

}  // namespace

std::unique_ptr<Renderer> Renderer::create(Context& ctx, const RendererDesc& desc,
                                           std::string& err) {
  std::unique_ptr<Renderer> r(new Renderer(ctx));
  if (!r->init(rendererDescDefaults(desc))) {
    err = r->error_;
    return nullptr;
  }
  return r;
}

bool Renderer::init(const RendererDesc& desc) {
  if (desc.width < 0 || desc.height < 0) return fail("renderer width/height must be >= 0");
  if (desc.mesh_capacity > kIndexMask) return fail("mesh_capacity above 2^20 - 1");
  if (!ctx_.makeCurrent()) return fail("cannot make the GL context current");
  std::string missing;
  if (!gl_->load(ctx_, missing)) {
    error_ = std::string("GL entry points missing on ") + ctx_.name() + ": " + missing;
    return false;
  }
  const GlApi& gl = *gl_;
  shared_ = ctx_.isShared();

  const char* version = reinterpret_cast<const char*>(gl.GetString(GL_VERSION));
  const char* renderer = reinterpret_cast<const char*>(gl.GetString(GL_RENDERER));
  gl_version_ = version ? version : "";
  gl_renderer_ = renderer ? renderer : "";
  int major = 0, minor = 0;
  if (!parseVersion(version, gles_, major, minor)) {
    error_ = "cannot parse GL_VERSION '" + gl_version_ + "'";
    return false;
  }
  // GL_VERSION is authoritative (a shared context may be either kind).
  const int need_minor = gles_ ? 0 : 3;
  if (major < 3 || (major == 3 && minor < need_minor)) {
    error_ = "GL " + gl_version_ + " is too old: need OpenGL ES 3.0 or OpenGL 3.3";
    return false;
  }
  etc2_ = (gles_ || major > 4 || (major == 4 && minor >= 3)) && gl.TexStorage2D && gl.CompressedTexSubImage2D;

  ScopedGlState guard(gl, shared_);
  impl_->bg_program =
      link(gl, gles_, shaders::kBackgroundVs, shaders::kBackgroundFs, error_);
  if (!impl_->bg_program) return false;
  impl_->mesh_program = link(gl, gles_, shaders::kMeshVs, shaders::kMeshFs, error_);
  if (!impl_->mesh_program) return false;
  impl_->item_program = link(gl, gles_, shaders::kMeshVs, shaders::kItemFs, error_);
  if (!impl_->item_program) return false;
  impl_->cap_color_program = link(gl, gles_, shaders::kMeshVs, shaders::kCaptureColorFs, error_);
  if (!impl_->cap_color_program) return false;
  impl_->cap_depth_program = link(gl, gles_, shaders::kMeshVs, shaders::kCaptureDepthFs, error_);
  if (!impl_->cap_depth_program) return false;
  impl_->tex_program = link(gl, gles_, shaders::kTexturedVs, shaders::kTexturedFs, error_);
  if (!impl_->tex_program) return false;
  impl_->bg = locate(gl, impl_->bg_program);
  impl_->mesh = locate(gl, impl_->mesh_program);
  impl_->item = locate(gl, impl_->item_program);
  impl_->cap_color = locate(gl, impl_->cap_color_program);
  impl_->cap_depth = locate(gl, impl_->cap_depth_program);
  impl_->tex = locate(gl, impl_->tex_program);
  if (desc.scaled_target) {
    impl_->up_program = link(gl, gles_, shaders::kUpscaleVs, shaders::kUpscaleFs, error_);
    if (!impl_->up_program) return false;
    impl_->up = locate(gl, impl_->up_program);
  }
  gl.GenVertexArrays(1, &impl_->empty_vao);

  // An RGBA8 + depth24 framebuffer of w x h; colour in a texture when
  // `color_tex` is given (the scaled target, sampled by the upscale pass),
  // else in a renderbuffer. (init's guard restores a host's bindings.)
  auto makeTarget = [&](int w, int h, GLuint& fbo, GLuint* color_rb, GLuint* color_tex, GLuint& depth) {
    if (color_tex) {
      gl.GenTextures(1, color_tex);
      gl.BindTexture(GL_TEXTURE_2D, *color_tex);
      gl.TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, w, h, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
      gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
      gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
      gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
      gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    } else {
      gl.GenRenderbuffers(1, color_rb);
      gl.BindRenderbuffer(GL_RENDERBUFFER, *color_rb);
      gl.RenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, w, h);
    }
    gl.GenRenderbuffers(1, &depth);
    gl.BindRenderbuffer(GL_RENDERBUFFER, depth);
    gl.RenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, w, h);
    gl.GenFramebuffers(1, &fbo);
    gl.BindFramebuffer(GL_FRAMEBUFFER, fbo);
    if (color_tex) gl.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, *color_tex, 0);
    else gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, *color_rb);
    gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth);
    const GLenum status = gl.CheckFramebufferStatus(GL_FRAMEBUFFER);
    if (status == GL_FRAMEBUFFER_COMPLETE) return true;
    char buf[96];
    std::snprintf(buf, sizeof buf, "framebuffer %dx%d incomplete (0x%04x)", w, h, status);
    return fail(buf);
  };
  if (!shared_) {
    fb_w_ = desc.width;
    fb_h_ = desc.height;
    if (!makeTarget(fb_w_, fb_h_, impl_->fbo, &impl_->color_rb, nullptr, impl_->depth_rb)) return false;
  }
  if (desc.scaled_target) {
    if (desc.width <= 0 || desc.height <= 0) return fail("scaled target needs the frame's width and height");
    impl_->scaled_w = desc.width;
    impl_->scaled_h = desc.height;
    if (!makeTarget(desc.width, desc.height, impl_->scaled_fbo, nullptr, &impl_->scaled_color_tex,
                    impl_->scaled_depth_rb))
      return false;
  }

  impl_->capacity = desc.mesh_capacity;
  impl_->slots.reserve(impl_->capacity);
  impl_->order.reserve(impl_->capacity * 2);
  impl_->free_slots.reserve(impl_->capacity);
  setLook(look_);
  if (!shared_) {
    const GLenum e = gl.GetError();
    if (e != GL_NO_ERROR) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "GL error 0x%04x during setup", e);
      return fail(buf);
    }
  }
  return true;
}

Renderer::~Renderer() {
  // Without the context current nothing can be freed; GL objects then die
  // with the context (or, for a host context, leak: the host switched away).
  if (!impl_ || !gl_->DeleteBuffers || !ctx_.makeCurrent()) return;
  const GlApi& gl = *gl_;
  ScopedGlState guard(gl, shared_);
  for (Slab& s : impl_->slabs) {
    gl.DeleteBuffers(1, &s.vbo);
    gl.DeleteBuffers(1, &s.ibo);
    if (!s.vaos.empty()) gl.DeleteVertexArrays(static_cast<GLsizei>(s.vaos.size()), s.vaos.data());
    if (s.atlas) gl.DeleteTextures(1, &s.atlas);
  }
  for (MeshSlot& s : impl_->slots) {
    if (!s.live || s.slab) continue;
    gl.DeleteVertexArrays(1, &s.vao);
    gl.DeleteBuffers(1, &s.vbo);
    gl.DeleteBuffers(1, &s.ibo);
    if (s.texture) gl.DeleteTextures(1, &s.texture);
  }
  for (GLuint p : {impl_->bg_program, impl_->mesh_program, impl_->item_program, impl_->cap_color_program,
                   impl_->cap_depth_program, impl_->tex_program, impl_->up_program})
    if (p) gl.DeleteProgram(p);
  if (impl_->empty_vao) gl.DeleteVertexArrays(1, &impl_->empty_vao);
  if (impl_->fbo) gl.DeleteFramebuffers(1, &impl_->fbo);
  if (impl_->color_rb) gl.DeleteRenderbuffers(1, &impl_->color_rb);
  if (impl_->depth_rb) gl.DeleteRenderbuffers(1, &impl_->depth_rb);
  if (impl_->scaled_fbo) gl.DeleteFramebuffers(1, &impl_->scaled_fbo);
  if (impl_->scaled_color_tex) gl.DeleteTextures(1, &impl_->scaled_color_tex);
  if (impl_->scaled_depth_rb) gl.DeleteRenderbuffers(1, &impl_->scaled_depth_rb);
}

void Renderer::setLook(const Look& look) {
  look_ = look;
  Impl& m = *impl_;
  // Sun azimuth is clockwise from north: east = sin, north = cos, and glTF z
  // points south.
  const double el = glm::radians(look.sun_elevation_deg);
  const double az = glm::radians(look.sun_azimuth_deg);
  m.sun_dir = glm::vec3(glm::normalize(glm::dvec3(std::sin(az) * std::cos(el), std::sin(el),
                                                  -std::cos(az) * std::cos(el))));
  // Tuned by eye on llvmpipe: a sunlit wall reaches ~0.9 of its albedo, a
  // shaded one ~0.35, so facades stay readable on every side.
  m.sun_color = glm::vec3(1.00f, 0.95f, 0.85f) * 0.75f;
  m.sky_ambient = glm::vec3(0.42f, 0.46f, 0.55f);
  m.ground_ambient = glm::vec3(0.25f, 0.24f, 0.22f);
  m.zenith = srgbToLinear(look.sky_zenith);
  m.horizon = srgbToLinear(look.sky_horizon);
  m.ground = srgbToLinear(look.ground);
}

bool Renderer::isValid(MeshHandle h) const {
  const uint32_t index = (h.id & kIndexMask) - 1;  // wraps to huge for id 0
  if (index >= impl_->slots.size()) return false;
  const MeshSlot& s = impl_->slots[index];
  return s.live && s.generation == (h.id >> kIndexBits);
}

MeshHandle Renderer::upload(const geo::MeshData& mesh) { return uploadOwn(mesh, false); }

MeshHandle Renderer::uploadLines(const geo::MeshData& mesh) { return uploadOwn(mesh, true); }

MeshHandle Renderer::uploadOwn(const geo::MeshData& mesh, bool lines) {
  if (lost()) return {};
  Impl& m = *impl_;
  // Prepared into a scratch arena kept between calls, then copied into GL
  // buffers of its own.
  int tw = 0, th = 0, tc = 0;
  if (!lines && !mesh.image.empty() && mesh.image.size() <= 0x7fffffff)
    stbi_info_from_memory(mesh.image.data(), static_cast<int>(mesh.image.size()), &tw, &th, &tc);
  const size_t need = preparedBytes(mesh.vertexCount(), mesh.indices.size(), tw, th);
  if (m.scratch.size() < need) m.scratch.resize(need);
  StagingArena arena{m.scratch.data(), m.scratch.size(), 0};
  PreparedMesh p;
  const bool ok = lines ? prepareLines(mesh, arena, p, error_) : prepareMesh(mesh, arena, p, error_);
  return ok ? place(p, 0) : MeshHandle{};
}

MeshHandle Renderer::uploadToSlab(SlabHandle slab, const PreparedMesh& mesh) {
  SlabUpload up;
  if (!beginSlabUpload(slab, mesh, up)) return {};
  bool finished = false;
  return continueSlabUpload(up, UINT64_MAX, finished);
}

bool Renderer::beginSlabUpload(SlabHandle h, const PreparedMesh& p, SlabUpload& up) {
  up = SlabUpload{};
  if (lost()) return false;
  if (h.id == 0 || h.id > impl_->slabs.size()) return fail("invalid slab handle");
  if (p.vertex_count == 0 || p.index_count == 0 || !p.vertices || !p.indices) return fail("mesh has no triangles");
  if (p.rgba && p.mip_levels < 1) return fail("prepared texture has no levels");
  if (!reserve(impl_->slabs[h.id - 1], p, up)) return false;
  up.slab = h.id;
  up.mesh = &p;
  return true;
}

// Bump placement into the buffers made at createSlab: no GL allocation.
bool Renderer::reserve(Slab& slab, const PreparedMesh& p, SlabUpload& up) {
  const uint64_t vbytes = p.vertexBytes(), ibytes = p.indexBytes();
  const uint64_t ioff = (slab.index_used + 3) & ~uint64_t(3), voff = slab.vertex_used;
  if (voff + vbytes > slab.desc.vertex_bytes || ioff + ibytes > slab.desc.index_bytes)
    return fail("slab full: vertex or index bytes exceed its size");
  if (slab.vaos_used >= slab.vaos.size()) return fail("slab full: mesh count exceeds its size");
  if (p.rgba && !placeImage(slab, p)) return false;
  up.voff = voff;
  up.ioff = ioff;
  up.texture = p.rgba ? slab.atlas : 0;
  const bool etc2 = slab.desc.atlas_format == AtlasFormat::Etc2;
  const uint64_t texels = etc2 ? atlasEtc2Bytes(p.texture_width, p.texture_height) : atlasUploadBytes(p);
  up.total = vbytes + ibytes + (p.rgba ? texels : 0);
  up.resets = slab.resets;
  slab.vertex_used = voff + vbytes;
  slab.index_used = ioff + ibytes;
  return true;
}

// Takes the image's place in the slab's atlas: on the grid, inside, and clear
// of every image placed since the last reset.
bool Renderer::placeImage(Slab& slab, const PreparedMesh& p) {
  if (!slab.atlas) return fail("slab has no atlas for a textured mesh");
  const int align = atlasAlign(slab.desc.atlas_format);
  const Slab::Place at{p.atlas_x, p.atlas_y, atlasRound(p.texture_width, align), atlasRound(p.texture_height, align)};
  if (at.x < 0 || at.y < 0 || at.x % align || at.y % align)
    return fail("atlas place of the image is not on the atlas grid");
  if (slab.desc.atlas_format == AtlasFormat::Etc2 && !p.etc2) return fail("an ETC2 atlas needs the image's ETC2 levels");
  if (at.x + at.w > slab.desc.atlas_width || at.y + at.h > slab.desc.atlas_height)
    return fail("slab full: the image's place is outside the atlas");
  for (const Slab::Place& o : slab.places)
    if (at.x < o.x + o.w && o.x < at.x + at.w && at.y < o.y + o.h && o.y < at.y + at.h)
      return fail("atlas place of the image overlaps another image");
  if (slab.places.size() >= slab.desc.meshes) return fail("slab full: mesh count exceeds its size");
  slab.places.push_back(at);
  slab.texture_used += atlasBytes(at.w, at.h, slab.desc.atlas_format);  // the place's texels, every level
  return true;
}

bool Renderer::beginSlabCopy(SlabHandle h, MeshHandle source, SlabUpload& up) {
  up = SlabUpload{};
  if (lost()) return false;
  if (h.id == 0 || h.id > impl_->slabs.size()) return fail("invalid slab handle");
  if (!isValid(source)) return fail("slab copy: invalid source mesh");
  const uint32_t index = (source.id & kIndexMask) - 1;
  const MeshSlot& src = impl_->slots[index];
  if (src.slab == 0) return fail("slab copy: the source mesh is not in a slab");
  if (src.texture) return fail("slab copy: the source mesh has a texture");
  PreparedMesh shape;
  shape.vertex_count = src.vertex_count;
  shape.index_count = static_cast<uint32_t>(src.index_count);
  shape.index16 = src.index_type == GL_UNSIGNED_SHORT;
  for (int k = 0; k < 3; ++k) shape.center[k] = src.center[k], shape.half[k] = src.half[k];
  std::copy(src.parts, src.parts + src.part_count, shape.parts);
  shape.part_count = src.part_count;
  if (!reserve(impl_->slabs[h.id - 1], shape, up)) return false;
  up.slab = h.id;
  up.shape = shape;
  up.source = source.id;
  up.source_resets = impl_->slabs[src.slab - 1].resets;
  return true;
}

MeshHandle Renderer::continueSlabUpload(SlabUpload& up, uint64_t max_bytes, bool& finished) {
  finished = true;
  if (up.slab == 0 || up.slab > impl_->slabs.size() || (!up.mesh && !up.source)) {
    fail("no slab upload in progress");
    return {};
  }
  Slab& slab = impl_->slabs[up.slab - 1];
  if (slab.resets != up.resets) {
    up.slab = 0;
    fail("slab upload abandoned: the slab was reset");
    return {};
  }
  if (!ctx_.makeCurrent()) {
    fail("GL context is not current on this thread");
    return {};
  }
  const PreparedMesh& p = up.source ? up.shape : *up.mesh;
  const uint64_t vbytes = p.vertexBytes(), ibytes = p.indexBytes();
  const uint64_t chunk_min = 4096;
  uint64_t allowance = std::max(max_bytes, chunk_min);
  const GlApi& gl = *gl_;
  {
    ScopedGlState guard(gl, shared_);
    // Both buffers are filled through GL_ARRAY_BUFFER: binding the index
    // buffer as GL_ELEMENT_ARRAY_BUFFER would need a vertex array bound.
    auto copyBuffer = [&](GLuint buffer, uint64_t base, const void* data, uint64_t begin, uint64_t size) {
      while (allowance > 0 && up.copied >= begin && up.copied < begin + size) {
        const uint64_t at = up.copied - begin, n = std::min(allowance, size - at);
        gl.BindBuffer(GL_ARRAY_BUFFER, buffer);
        gl.BufferSubData(GL_ARRAY_BUFFER, static_cast<GLintptr>(base + at), static_cast<GLsizeiptr>(n),
                         static_cast<const uint8_t*>(data) + at);
        up.copied += n;
        allowance -= n;
      }
    };
    // A copy: from the source's slab buffers, GPU to GPU. The source is
    // checked again each step (its slab must not have been reset).
    auto copyGpu = [&](GLuint from, uint64_t from_base, GLuint to, uint64_t to_base, uint64_t begin, uint64_t size) {
      while (allowance > 0 && up.copied >= begin && up.copied < begin + size) {
        const uint64_t at = up.copied - begin, n = std::min(allowance, size - at);
        gl.BindBuffer(GL_COPY_READ_BUFFER, from);
        gl.BindBuffer(GL_COPY_WRITE_BUFFER, to);
        gl.CopyBufferSubData(GL_COPY_READ_BUFFER, GL_COPY_WRITE_BUFFER, static_cast<GLintptr>(from_base + at),
                             static_cast<GLintptr>(to_base + at), static_cast<GLsizeiptr>(n));
        up.copied += n;
        allowance -= n;
      }
    };
    if (up.source) {
      const MeshHandle source{up.source};
      const MeshSlot* src = isValid(source) ? &impl_->slots[(source.id & kIndexMask) - 1] : nullptr;
      if (!src || src->slab == 0 || impl_->slabs[src->slab - 1].resets != up.source_resets) {
        up.slab = 0;
        fail("slab copy abandoned: the source mesh is gone");
        return {};
      }
      copyGpu(src->vbo, src->vertex_offset, slab.vbo, up.voff, 0, vbytes);
      copyGpu(src->ibo, src->index_offset, slab.ibo, up.ioff, vbytes, ibytes);
    } else {
      copyBuffer(slab.vbo, up.voff, p.vertices, 0, vbytes);
      copyBuffer(slab.ibo, up.ioff, p.indices, vbytes, ibytes);
    }
    if (p.rgba && allowance > 0 && up.copied < up.total) {
      if (slab.desc.atlas_format == AtlasFormat::Etc2) copyEtc2Levels(up, p, vbytes + ibytes, allowance);
      else copyRgbaLevels(up, p, vbytes + ibytes, allowance);
    }
  }
  if (up.copied < up.total) {
    finished = false;
    return {};
  }
  const MeshHandle handle = place(p, up.slab, &up);
  up.slab = 0;
  return handle;
}

// The atlas's levels in order, whole rows at a time, each from the image's
// level into its place's corner (uv_scale and uv_offset map it), then the
// place's edge padded.
void Renderer::copyRgbaLevels(SlabUpload& up, const PreparedMesh& p, uint64_t begin, uint64_t& allowance) {
  const GlApi& gl = *gl_;
  bindAtlasForUpload(gl, up.texture, shared_);
  gl.PixelStorei(GL_UNPACK_ALIGNMENT, 4);
  uint64_t level_begin = begin;
  const int x0 = p.atlas_x, y0 = p.atlas_y, cw = atlasRound(p.texture_width), ch = atlasRound(p.texture_height);
  for (int l = 0; l < kAtlasLevels && allowance > 0; ++l) {
    int w = 0, h = 0;
    const uint8_t* texels = atlasSource(p, l, w, h);
    const uint64_t row = uint64_t(w) * 4, size = row * uint64_t(h);
    if (up.copied < level_begin + size) {
      const int y = static_cast<int>((up.copied - level_begin) / row);
      const int rows = static_cast<int>(std::clamp<uint64_t>(allowance / row, 1, uint64_t(h - y)));
      gl.TexSubImage2D(GL_TEXTURE_2D, l, x0 >> l, (y0 >> l) + y, w, rows, GL_RGBA, GL_UNSIGNED_BYTE,
                       texels + row * uint64_t(y));
      const uint64_t n = row * uint64_t(rows);
      up.copied += n;
      allowance -= std::min(allowance, n);
      if (y + rows < h) break;  // the level is not done: the allowance is
      padLevel(gl, l, texels, x0 >> l, y0 >> l, w, h, std::max(1, cw >> l), std::max(1, ch >> l));
    }
    level_begin += size;
  }
}

// The same for an ETC2 atlas: the place's blocks, every level, whole rows of
// blocks at a time (the preparing thread encoded the padding with them). The
// allowance is charged the RGBA8 bytes the blocks stand for (8 a block byte):
// a driver without ETC2 in hardware (Mesa's llvmpipe) decodes them in the call,
// and a chunk must not hold 8 times the texels of an RGBA8 one.
void Renderer::copyEtc2Levels(SlabUpload& up, const PreparedMesh& p, uint64_t begin, uint64_t& allowance) {
  constexpr uint64_t kCharge = 8;
  const GlApi& gl = *gl_;
  bindAtlasForUpload(gl, up.texture, shared_);
  uint64_t level_begin = begin;
  for (int l = 0; l < kAtlasLevels && allowance > 0; ++l) {
    int w = 0, h = 0;
    const uint8_t* blocks = atlasEtc2Level(p, l, w, h);
    const uint64_t row = uint64_t(w / 4) * kEtc2BlockBytes, size = row * uint64_t(h / 4);
    if (up.copied < level_begin + size) {
      const int y = static_cast<int>((up.copied - level_begin) / row);
      const int rows = static_cast<int>(std::clamp<uint64_t>(allowance / (row * kCharge), 1, uint64_t(h / 4 - y)));
      gl.CompressedTexSubImage2D(GL_TEXTURE_2D, l, p.atlas_x >> l, (p.atlas_y >> l) + 4 * y, w, 4 * rows,
                                 GL_COMPRESSED_RGB8_ETC2, static_cast<GLsizei>(row * uint64_t(rows)),
                                 blocks + row * uint64_t(y));
      const uint64_t n = row * uint64_t(rows);
      up.copied += n;
      allowance -= std::min(allowance, n * kCharge);
      if (y + rows < h / 4) break;
    }
    level_begin += size;
  }
}

bool Renderer::reserveMeshes(uint32_t more) {
  Impl& m = *impl_;
  if (uint64_t(m.capacity) + more > kIndexMask) return fail("mesh_capacity above 2^20 - 1");
  m.capacity += more;
  m.slots.reserve(m.capacity);
  m.order.reserve(size_t(m.capacity) * 2);
  m.free_slots.reserve(m.capacity);
  return true;
}

MeshHandle Renderer::place(const PreparedMesh& p, uint32_t slab_id, const SlabUpload* copied) {
  Impl& m = *impl_;
  Slab* slab = slab_id ? &m.slabs[slab_id - 1] : nullptr;
  if (p.vertex_count == 0 || p.index_count == 0 || (!(copied && copied->source) && (!p.vertices || !p.indices))) {
    fail("mesh has no triangles");
    return {};
  }
  if (m.free_slots.empty() && m.slots.size() >= m.capacity) {
    fail("mesh pool full (RendererDesc::mesh_capacity)");
    return {};
  }
  if (!ctx_.makeCurrent()) {
    fail("GL context is not current on this thread");
    return {};
  }
  const uint64_t vbytes = p.vertexBytes(), ibytes = p.indexBytes();
  // Slab meshes arrive here copied (beginSlabUpload placed them).
  if (slab && !copied) {
    fail("slab meshes are placed by beginSlabUpload");
    return {};
  }
  const uint64_t voff = copied ? copied->voff : 0, ioff = copied ? copied->ioff : 0;

  uint32_t index;
  if (!m.free_slots.empty()) {
    index = m.free_slots.back();
    m.free_slots.pop_back();
  } else {
    index = static_cast<uint32_t>(m.slots.size());
    m.slots.emplace_back();
  }
  MeshSlot& s = m.slots[index];

  const GlApi& gl = *gl_;
  {
    ScopedGlState guard(gl, shared_);
    if (slab) {
      s.vao = slab->vaos[slab->vaos_used++];
      s.vbo = slab->vbo;
      s.ibo = slab->ibo;
    } else {
      gl.GenVertexArrays(1, &s.vao);
      gl.GenBuffers(1, &s.vbo);
      gl.GenBuffers(1, &s.ibo);
    }
    // VAO first: the element buffer binding below is VAO state, and must not
    // land in whatever VAO the host had bound.
    gl.BindVertexArray(s.vao);
    gl.BindBuffer(GL_ARRAY_BUFFER, s.vbo);
    if (!slab) gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vbytes), p.vertices, GL_STATIC_DRAW);
    gl.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, s.ibo);
    if (!slab) gl.BufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(ibytes), p.indices, GL_STATIC_DRAW);
    // Normal and colour share their bytes with the uv (prepared_mesh.h): each
    // program reads only what its kind of mesh holds.
    gl.EnableVertexAttribArray(0);
    gl.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, kVertexBytes, byteOffset(voff + 0));
    gl.EnableVertexAttribArray(1);
    gl.VertexAttribPointer(1, 3, GL_BYTE, GL_TRUE, kVertexBytes, byteOffset(voff + 12));
    gl.EnableVertexAttribArray(2);
    gl.VertexAttribPointer(2, 4, GL_UNSIGNED_BYTE, GL_TRUE, kVertexBytes, byteOffset(voff + 16));
    gl.EnableVertexAttribArray(3);
    gl.VertexAttribPointer(3, 2, GL_FLOAT, GL_FALSE, kVertexBytes, byteOffset(voff + 12));
    gl.BindVertexArray(0);
    if (p.rgba && slab) {
      // Texels and mip levels are in already (continueSlabUpload).
      s.texture = copied->texture;
      s.uv_scale[0] = float(p.texture_width) / float(slab->desc.atlas_width);
      s.uv_scale[1] = float(p.texture_height) / float(slab->desc.atlas_height);
      s.uv_offset[0] = float(p.atlas_x) / float(slab->desc.atlas_width);
      s.uv_offset[1] = float(p.atlas_y) / float(slab->desc.atlas_height);
    } else if (p.rgba) {
      // Impostor texture, with mipmaps so a far impostor does not shimmer.
      // A host's bound unpack buffer or row length would redirect the copy.
      gl.ActiveTexture(GL_TEXTURE0);
      if (shared_) {
        gl.BindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
        gl.PixelStorei(GL_UNPACK_ROW_LENGTH, 0);
      }
      gl.PixelStorei(GL_UNPACK_ALIGNMENT, 4);
      {
        gl.GenTextures(1, &s.texture);
        gl.BindTexture(GL_TEXTURE_2D, s.texture);
        gl.TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, p.texture_width, p.texture_height, 0, GL_RGBA,
                      GL_UNSIGNED_BYTE, p.rgba);
        setTextureSampling(gl);
      }
      gl.GenerateMipmap(GL_TEXTURE_2D);
      gl.BindTexture(GL_TEXTURE_2D, 0);
    }
  }

  s.index_count = static_cast<GLsizei>(p.index_count);
  s.index_type = p.index16 ? GL_UNSIGNED_SHORT : GL_UNSIGNED_INT;
  s.index_offset = ioff;
  s.vertex_offset = voff;
  s.vertex_count = p.vertex_count;
  s.slab = slab_id;
  s.center = glm::dvec3(p.center[0], p.center[1], p.center[2]);
  s.half = glm::dvec3(p.half[0], p.half[1], p.half[2]);
  s.bytes = vbytes + ibytes + (p.rgba ? p.textureBytes() * 4 / 3 : 0);
  std::copy(p.parts, p.parts + p.part_count, s.parts);
  s.part_count = p.part_count;
  s.lines = p.lines;
  s.live = true;
  if (slab) {
    slab->meshes.push_back(index);  // reserved for desc.meshes at createSlab
  }
  ++live_meshes_;
  mesh_bytes_ += s.bytes;
  return MeshHandle{(s.generation << kIndexBits) | (index + 1)};
}

uint64_t slabGpuBytes(const SlabDesc& d) {
  return d.vertex_bytes + d.index_bytes + atlasBytes(d.atlas_width, d.atlas_height, d.atlas_format);
}

SlabHandle Renderer::createSlab(const SlabDesc& d) {
  Impl& m = *impl_;
  out_of_memory_ = false;
  if (lost()) return {};
  if (d.meshes == 0 || d.vertex_bytes == 0 || d.index_bytes == 0) {
    fail("slab needs meshes, vertex bytes and index bytes");
    return {};
  }
  if (d.vertex_bytes > 0x7fffffffull || d.index_bytes > 0x7fffffffull) {
    fail("slab larger than 2 GiB");
    return {};
  }
  const int align = atlasAlign(d.atlas_format);
  if ((d.atlas_width || d.atlas_height) &&
      (d.atlas_width <= 0 || d.atlas_height <= 0 || d.atlas_width > 16384 || d.atlas_height > 16384 ||
       d.atlas_width % align || d.atlas_height % align)) {
    char msg[96];
    std::snprintf(msg, sizeof msg, "slab atlas size out of range (1..16384, a multiple of %d)", align);
    fail(msg);
    return {};
  }
  if (d.atlas_width && d.atlas_format == AtlasFormat::Etc2 && !etc2_) {
    fail(("an ETC2 slab atlas needs OpenGL ES 3.0 or OpenGL 4.3 (GL_VERSION " + gl_version_ + ")").c_str());
    return {};
  }
  if (!ctx_.makeCurrent()) {
    fail("GL context is not current on this thread");
    return {};
  }
  m.slabs.emplace_back();
  Slab& s = m.slabs.back();
  s.desc = d;
  s.vaos.resize(d.meshes);
  s.meshes.reserve(d.meshes);
  s.places.reserve(d.meshes);
  const GlApi& gl = *gl_;
  ScopedGlState guard(gl, shared_);
  gl.GenBuffers(1, &s.vbo);
  gl.GenBuffers(1, &s.ibo);
  gl.BindVertexArray(0);
  gl.BindBuffer(GL_ARRAY_BUFFER, s.vbo);
  gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(d.vertex_bytes), nullptr, GL_DYNAMIC_DRAW);
  gl.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, s.ibo);
  gl.BufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(d.index_bytes), nullptr, GL_DYNAMIC_DRAW);
  gl.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, 0);
  gl.GenVertexArrays(static_cast<GLsizei>(d.meshes), s.vaos.data());
  if (d.atlas_width) {
    // Every level is allocated here; uploads only fill them.
    gl.GenTextures(1, &s.atlas);
    gl.ActiveTexture(GL_TEXTURE0);
    gl.BindTexture(GL_TEXTURE_2D, s.atlas);
    if (d.atlas_format == AtlasFormat::Etc2)
      gl.TexStorage2D(GL_TEXTURE_2D, kAtlasLevels, GL_COMPRESSED_RGB8_ETC2, d.atlas_width, d.atlas_height);
    else
      for (int level = 0; level < kAtlasLevels; ++level)
        gl.TexImage2D(GL_TEXTURE_2D, level, GL_RGBA8, d.atlas_width >> level, d.atlas_height >> level, 0, GL_RGBA,
                      GL_UNSIGNED_BYTE, nullptr);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, kAtlasLevels - 1);
    setTextureSampling(gl);
    gl.BindTexture(GL_TEXTURE_2D, 0);
  }
  // A driver that cannot back the slab says so here (GL_OUT_OF_MEMORY leaves
  // the objects undefined, GLES 3.0 §2.5), not later as frames without cells.
  GLenum e = GL_NO_ERROR;
  for (GLenum next; (next = gl.GetError()) != GL_NO_ERROR;) e = e == GL_NO_ERROR ? next : e;
  if (e != GL_NO_ERROR) {
    gl.DeleteBuffers(1, &s.vbo);
    gl.DeleteBuffers(1, &s.ibo);
    gl.DeleteVertexArrays(static_cast<GLsizei>(s.vaos.size()), s.vaos.data());
    if (s.atlas) gl.DeleteTextures(1, &s.atlas);
    m.slabs.pop_back();
    out_of_memory_ = e == GL_OUT_OF_MEMORY;
    char msg[200];
    std::snprintf(msg, sizeof msg, "GL %s allocating a cell slab (%llu vertex, %llu index bytes, a %dx%d atlas)",
                  out_of_memory_ ? "out of memory" : "error", static_cast<unsigned long long>(d.vertex_bytes),
                  static_cast<unsigned long long>(d.index_bytes), d.atlas_width, d.atlas_height);
    fail(msg);
    return {};
  }
  gpu_slab_bytes_ += slabGpuBytes(d);
  return SlabHandle{static_cast<uint32_t>(m.slabs.size())};
}

uint64_t Renderer::measuredSlabBytes(bool& textures_known) {
  textures_known = gl_->GetTexLevelParameteriv != nullptr;
  if (!ctx_.makeCurrent()) return 0;
  const GlApi& gl = *gl_;
  ScopedGlState guard(gl, shared_);
  constexpr GLenum kTextureWidth = 0x1000, kTextureHeight = 0x1001;  // GL_TEXTURE_WIDTH / HEIGHT
  uint64_t bytes = 0;
  gl.BindVertexArray(0);
  for (const Slab& s : impl_->slabs) {
    for (GLuint b : {s.vbo, s.ibo}) {
      GLint64 size = 0;
      gl.BindBuffer(GL_ARRAY_BUFFER, b);
      gl.GetBufferParameteri64v(GL_ARRAY_BUFFER, GL_BUFFER_SIZE, &size);
      bytes += uint64_t(size);
    }
    if (!textures_known || !s.atlas) continue;
    gl.BindTexture(GL_TEXTURE_2D, s.atlas);
    for (GLint level = 0; level < kAtlasLevels; ++level) {
      GLint w = 0, h = 0;
      gl.GetTexLevelParameteriv(GL_TEXTURE_2D, level, kTextureWidth, &w);
      gl.GetTexLevelParameteriv(GL_TEXTURE_2D, level, kTextureHeight, &h);
      if (w <= 0 || h <= 0) break;
      bytes += s.desc.atlas_format == AtlasFormat::Etc2 ? uint64_t((w + 3) / 4) * uint64_t((h + 3) / 4) * 8
                                                        : uint64_t(w) * uint64_t(h) * 4;
    }
  }
  gl.BindBuffer(GL_ARRAY_BUFFER, 0);
  gl.BindTexture(GL_TEXTURE_2D, 0);
  return bytes;
}

void Renderer::resetSlab(SlabHandle h) {
  if (h.id == 0 || h.id > impl_->slabs.size()) return;
  Slab& s = impl_->slabs[h.id - 1];
  // Copy-free: release() swaps each slot back to the free list.
  while (!s.meshes.empty()) {
    const uint32_t index = s.meshes.back();
    const MeshSlot& ms = impl_->slots[index];
    release(MeshHandle{(ms.generation << kIndexBits) | (index + 1)});
  }
  s.vertex_used = s.index_used = s.texture_used = 0;
  s.vaos_used = 0;
  s.places.clear();
  ++s.resets;
}

SlabUsage Renderer::slabUsage(SlabHandle h) const {
  SlabUsage u;
  if (h.id == 0 || h.id > impl_->slabs.size()) return u;
  const Slab& s = impl_->slabs[h.id - 1];
  u.vertex_bytes = s.vertex_used;
  u.index_bytes = s.index_used;
  u.meshes = s.vaos_used;
  u.textures = static_cast<uint32_t>(s.places.size());
  u.texture_bytes = s.texture_used;
  return u;
}

void Renderer::release(MeshHandle h) {
  if (!isValid(h) || !ctx_.makeCurrent()) return;
  const uint32_t index = (h.id & kIndexMask) - 1;
  MeshSlot& s = impl_->slots[index];
  if (s.slab) {
    // The slab keeps its buffers; only its placement list forgets the mesh.
    auto& list = impl_->slabs[s.slab - 1].meshes;
    for (size_t i = 0; i < list.size(); ++i)
      if (list[i] == index) {
        list[i] = list.back();
        list.pop_back();
        break;
      }
  } else {
    const GlApi& gl = *gl_;
    ScopedGlState guard(gl, shared_);
    gl.DeleteVertexArrays(1, &s.vao);
    gl.DeleteBuffers(1, &s.vbo);
    gl.DeleteBuffers(1, &s.ibo);
    if (s.texture) gl.DeleteTextures(1, &s.texture);
  }
  live_meshes_ -= 1;
  mesh_bytes_ -= s.bytes;
  const uint32_t generation = s.generation;
  s = MeshSlot{};
  // Generation 0 is skipped so a handle never equals a bare index.
  s.generation = (generation & kGenerationMask) == kGenerationMask ? 1 : generation + 1;
  impl_->free_slots.push_back(index);
}

// What every draw of a frame shares: the eye, the view and clip transforms,
// the frustum and the fog.
struct FrameView {
  glm::dvec3 eye;
  glm::dmat4 view, clip;
  glm::mat4 clip_f;
  Frustum frustum;
  float inv_fog2;
};

namespace {

FrameView frameView(const Camera& cam, const Look& look) {
  FrameView v;
  v.eye = enuToGltf(cam.eye_enu);
  v.view = viewRotation(cam);
  v.clip = projection(cam) * v.view;
  v.clip_f = glm::mat4(v.clip);
  v.frustum = Frustum::fromClip(v.clip);
  const float fog_d = look.fog_distance_m > 0.0f ? look.fog_distance_m : static_cast<float>(0.4 * cam.far_m);
  v.inv_fog2 = 1.0f / (fog_d * fog_d);
  return v;
}

void applyLook(const GlApi& gl, const Renderer::Impl& m, const Uniforms& u, float inv_fog2) {
  gl.Uniform3f(u.sun_dir, m.sun_dir.x, m.sun_dir.y, m.sun_dir.z);
  gl.Uniform3f(u.sun_color, m.sun_color.x, m.sun_color.y, m.sun_color.z);
  gl.Uniform3f(u.sky_ambient, m.sky_ambient.x, m.sky_ambient.y, m.sky_ambient.z);
  gl.Uniform3f(u.ground_ambient, m.ground_ambient.x, m.ground_ambient.y, m.ground_ambient.z);
  gl.Uniform3f(u.horizon, m.horizon.x, m.horizon.y, m.horizon.z);
  gl.Uniform1f(u.inv_fog2, inv_fog2);
}

// Sky and ground go last, only where no mesh landed (depth still 1.0):
// llvmpipe then shades each covered pixel once instead of twice.
void drawBackground(const GlApi& gl, const Renderer::Impl& m, const Camera& cam, const FrameView& v, FrameStats& fs) {
  // Camera-to-world rotation is the transpose of the view rotation; its
  // columns are right, up and back in world axes.
  const glm::dmat3 cam_to_world = glm::transpose(glm::dmat3(v.view));
  const double ty = std::tan(glm::radians(cam.fov_y_deg) * 0.5);
  const double tx = ty * static_cast<double>(cam.width) / static_cast<double>(cam.height);
  const glm::mat3 basis(glm::vec3(cam_to_world[0] * tx), glm::vec3(cam_to_world[1] * ty),
                        glm::vec3(-cam_to_world[2]));
  gl.UseProgram(m.bg_program);
  applyLook(gl, m, m.bg, v.inv_fog2);
  gl.UniformMatrix3fv(m.bg.ray_basis, 1, GL_FALSE, &basis[0][0]);
  gl.Uniform3f(m.bg.zenith, m.zenith.x, m.zenith.y, m.zenith.z);
  gl.Uniform3f(m.bg.ground, m.ground.x, m.ground.y, m.ground.z);
  gl.Uniform1f(m.bg.eye_height, static_cast<float>(v.eye.y));
  gl.Disable(GL_CULL_FACE);
  gl.DepthFunc(GL_LEQUAL);  // the triangle sits exactly on the far plane
  gl.DepthMask(GL_FALSE);
  gl.BindVertexArray(m.empty_vao);
  gl.DrawArrays(GL_TRIANGLES, 0, 3);
  gl.DepthMask(GL_TRUE);
  ++fs.draw_calls;
}

void setDepthRange(const GlApi& gl, float near_d, float far_d) {
  if (gl.DepthRangef) gl.DepthRangef(near_d, far_d);
  else if (gl.DepthRange) gl.DepthRange(near_d, far_d);
}

// The pass's target, viewport (clears stay inside this view: a frame may hold
// several), fixed state, and cleared buffers.
void beginPass(const GlApi& gl, const Renderer::Impl& m, const Camera& cam, const RenderOptions& opt, bool scaled,
               bool shared) {
  const Pass pass = opt.pass;
  // Scaled views draw into the scaled target and are blitted at the end.
  if (scaled) gl.BindFramebuffer(GL_FRAMEBUFFER, m.scaled_fbo);
  else if (!shared) gl.BindFramebuffer(GL_FRAMEBUFFER, m.fbo);
  gl.Viewport(cam.viewport_x, cam.viewport_y, cam.width, cam.height);
  gl.Enable(GL_SCISSOR_TEST);
  gl.Scissor(cam.viewport_x, cam.viewport_y, cam.width, cam.height);
  gl.Disable(GL_STENCIL_TEST);
  gl.Disable(GL_BLEND);
  gl.Disable(GL_POLYGON_OFFSET_FILL);
  gl.Disable(GL_RASTERIZER_DISCARD);
  gl.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  gl.DepthMask(GL_TRUE);
  gl.Enable(GL_DEPTH_TEST);
  setDepthRange(gl, 0.f, 1.f);
  if (gl.ClearDepthf) gl.ClearDepthf(1.0f);
  if (pass == Pass::Shaded) {
    gl.Clear(GL_DEPTH_BUFFER_BIT);
  } else {
    // Bake captures start from nothing: transparent black, far depth.
    gl.ClearColor(0.0f, 0.0f, 0.0f, 0.0f);
    gl.Clear(opt.keep_depth ? GL_COLOR_BUFFER_BIT : GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  }
  if (pass == Pass::CaptureColor || pass == Pass::CaptureDepth) {
    gl.Disable(GL_CULL_FACE);
  } else {
    gl.Enable(GL_CULL_FACE);
    gl.CullFace(GL_BACK);
    gl.FrontFace(cam.mirror ? GL_CW : GL_CCW);  // a mirrored projection flips the winding
  }
  gl.DepthFunc(opt.keep_depth ? GL_LEQUAL : GL_LESS);
}

// The program (and its uniforms) that draws the pass's untextured meshes, or
// (textured) its impostors: false when the pass draws none.
bool passProgram(const Renderer::Impl& m, Pass pass, bool textured, GLuint& program, const Uniforms*& u) {
  if (textured) {
    // An item buffer shows impostors too (flat, in their ids); captures never hold them.
    if (pass == Pass::Shaded) program = m.tex_program, u = &m.tex;
    else if (pass == Pass::ItemBuffer) program = m.item_program, u = &m.item;
    else return false;
    return true;
  }
  switch (pass) {
    case Pass::Shaded: program = m.mesh_program, u = &m.mesh; break;
    case Pass::ItemBuffer: program = m.item_program, u = &m.item; break;
    case Pass::CaptureColor: program = m.cap_color_program, u = &m.cap_color; break;
    case Pass::CaptureDepth: program = m.cap_depth_program, u = &m.cap_depth; break;
  }
  return true;
}

// Stretches the scaled view over the real one: a textured triangle over the
// viewport, bilinear (cheaper than a linear glBlitFramebuffer on llvmpipe,
// decision 0008 §7). Only colour goes to the destination; its depth is left alone.
void stretchScaled(const GlApi& gl, const Renderer::Impl& m, const Camera& out, const Camera& cam, bool shared,
                   FrameStats& fs) {
  gl.BindFramebuffer(GL_FRAMEBUFFER, shared ? static_cast<GLuint>(m.host_fbo) : m.fbo);
  gl.Viewport(out.viewport_x, out.viewport_y, out.width, out.height);
  gl.Scissor(out.viewport_x, out.viewport_y, out.width, out.height);
  gl.Disable(GL_DEPTH_TEST);
  gl.DepthMask(GL_FALSE);
  gl.Disable(GL_CULL_FACE);
  gl.UseProgram(m.up_program);
  gl.ActiveTexture(GL_TEXTURE0);
  gl.BindTexture(GL_TEXTURE_2D, m.scaled_color_tex);
  gl.Uniform1i(m.up.texture, 0);
  const float tw = static_cast<float>(m.scaled_w), th = static_cast<float>(m.scaled_h);
  gl.Uniform2f(m.up.uv_scale, static_cast<float>(cam.width) / tw, static_cast<float>(cam.height) / th);
  gl.Uniform4f(m.up.uv_clamp, 0.5f / tw, 0.5f / th, (static_cast<float>(cam.width) - 0.5f) / tw,
               (static_cast<float>(cam.height) - 0.5f) / th);
  gl.BindVertexArray(m.empty_vao);
  gl.DrawArrays(GL_TRIANGLES, 0, 3);
  gl.DepthMask(GL_TRUE);
  ++fs.draw_calls;
}

}  // namespace

// Why a frame cannot be drawn as asked, or null.
const char* Renderer::checkRender(const Camera& out, const MeshHandle* list, size_t n, const RenderOptions& opt) const {
  if (const char* bad = validateCamera(out)) return bad;
  if (!(opt.scale > 0.0 && opt.scale <= 1.0)) return "render scale outside (0, 1]";
  const bool scaled = opt.pass == Pass::Shaded && opt.scale < 1.0;
  if (scaled && !impl_->scaled_fbo) return "render scale < 1 needs RendererDesc::scaled_target";
  if (scaled && (out.width > impl_->scaled_w || out.height > impl_->scaled_h)) return "view is larger than the scaled target";
  if (out.viewport_x < 0 || out.viewport_y < 0) return "camera viewport starts outside the framebuffer";
  if (!shared_ && (out.viewport_x + out.width > fb_w_ || out.viewport_y + out.height > fb_h_))
    return "camera viewport is larger than the renderer's framebuffer";
  if (n > 0 && !list) return "draw list is null";
  if (opt.pass == Pass::ItemBuffer && n > 0 && !opt.item_ids) return "item buffer pass without item ids";
  if (opt.keep_depth && opt.pass != Pass::ItemBuffer) return "keep_depth outside an item buffer pass";
  return nullptr;
}

namespace {

// A mesh's triangles: whole, or those of its parts the frustum keeps, each
// run of adjacent kept parts in one call.
void drawParts(const GlApi& gl, const MeshSlot& s, const glm::dvec3& rel, const Frustum& frustum, FrameStats& fs) {
  const uint64_t index_size = s.index_type == GL_UNSIGNED_SHORT ? 2 : 4;
  auto draw = [&](uint32_t first, uint32_t count) {
    gl.DrawElements(s.lines ? GL_LINES : GL_TRIANGLES, GLsizei(count), s.index_type,
                    byteOffset(s.index_offset + first * index_size));
    ++fs.draw_calls;
    if (!s.lines) fs.triangles += count / 3;
  };
  if (s.part_count < 2) return draw(0, uint32_t(s.index_count));
  uint32_t first = 0, count = 0;
  for (int k = 0; k < s.part_count; ++k) {
    const MeshPart& p = s.parts[k];
    const glm::dvec3 lo(p.lo[0], p.lo[1], p.lo[2]), hi(p.hi[0], p.hi[1], p.hi[2]);
    if (!frustum.intersectsBox(rel + (lo + hi) * 0.5, (hi - lo) * 0.5)) {
      ++fs.parts_culled;
      continue;
    }
    if (count && first + count != p.first) {
      draw(first, count);
      count = 0;
    }
    if (!count) first = p.first;
    count += p.count;
  }
  if (count) draw(first, count);
}

}  // namespace

// The meshes list[from, to) with (textured) or without a texture that the
// frustum keeps, nearest first, with the pass's program.
void Renderer::drawMeshes(const Camera& cam, const MeshHandle* list, size_t from, size_t to, const RenderOptions& opt,
                          const FrameView& v, bool textured, FrameStats& fs) {
  const GlApi& gl = *gl_;
  Impl& m = *impl_;
  GLuint program = 0;
  const Uniforms* u = nullptr;
  if (!passProgram(m, opt.pass, textured, program, u)) return;
  m.order.clear();
  for (size_t i = from; i < to; ++i) {
    if (!isValid(list[i])) {
      if (!textured) ++fs.meshes_invalid;
      continue;
    }
    const MeshSlot& s = m.slots[(list[i].id & kIndexMask) - 1];
    if ((s.texture != 0) != textured) continue;
    const glm::dvec3 rel = s.center - v.eye;
    if (!v.frustum.intersectsBox(rel, s.half)) {
      ++fs.meshes_culled;
      continue;
    }
    // Reserved for twice the pool; only a list longer than that grows it.
    m.order.emplace_back(static_cast<float>(glm::length(rel) - glm::length(s.half)), static_cast<uint32_t>(i));
  }
  std::sort(m.order.begin(), m.order.end());
  const bool shaded_tex = textured && opt.pass == Pass::Shaded;
  bool bound = false;
  for (const auto& entry : m.order) {
    const size_t i = entry.second;
    const MeshSlot& s = m.slots[(list[i].id & kIndexMask) - 1];
    const glm::dvec3 rel = s.center - v.eye;
    if (!bound) {
      bound = true;
      gl.UseProgram(program);
      applyLook(gl, m, *u, v.inv_fog2);
      gl.UniformMatrix4fv(u->viewproj, 1, GL_FALSE, &v.clip_f[0][0]);
      if (opt.pass == Pass::CaptureDepth) {
        const glm::dvec3 f = viewForward(cam);
        gl.Uniform3f(u->forward, float(f.x), float(f.y), float(f.z));
        gl.Uniform1f(u->depth_scale, float(16777215.0 / opt.max_depth_m));
      }
      if (shaded_tex) {
        gl.ActiveTexture(GL_TEXTURE0);
        gl.Uniform1i(u->texture, 0);
      }
    }
    if (opt.pass == Pass::ItemBuffer) {
      const uint32_t id = opt.item_ids[i];
      gl.Uniform4f(u->item, float(id & 255u) / 255.0f, float((id >> 8) & 255u) / 255.0f,
                   float((id >> 16) & 255u) / 255.0f, 1.0f);
    }
    if (shaded_tex) {
      gl.BindTexture(GL_TEXTURE_2D, s.texture);
      gl.Uniform2f(u->uv_scale, s.uv_scale[0], s.uv_scale[1]);
      gl.Uniform2f(u->uv_offset, s.uv_offset[0], s.uv_offset[1]);
    }
    gl.Uniform3f(u->offset, static_cast<float>(rel.x), static_cast<float>(rel.y), static_cast<float>(rel.z));
    gl.BindVertexArray(s.vao);
    drawParts(gl, s, rel, v.frustum, fs);
    ++fs.meshes_drawn;
  }
}

bool Renderer::render(const Camera& out, const MeshHandle* list, size_t n, FrameStats* stats,
                      const RenderOptions& opt) {
  if (const char* bad = checkRender(out, list, n, opt)) return fail(bad);
  if (lost()) return false;
  if (!ctx_.makeCurrent()) return fail("GL context is not current on this thread");
  // Scaled: the same camera over fewer pixels of the scaled target, stretched
  // over the view afterwards (the aspect ratio is kept to within a pixel).
  const bool scaled = opt.pass == Pass::Shaded && opt.scale < 1.0;
  Camera cam = out;
  if (scaled) {
    cam.width = std::max(1, static_cast<int>(std::lround(out.width * opt.scale)));
    cam.height = std::max(1, static_cast<int>(std::lround(out.height * opt.scale)));
    cam.viewport_x = cam.viewport_y = 0;
  }
  const auto t0 = std::chrono::steady_clock::now();
  const GlApi& gl = *gl_;
  Impl& m = *impl_;
  FrameStats fs;
  const FrameView v = frameView(cam, look_);
  {
    ScopedGlState guard(gl, shared_);
    if (shared_) m.host_fbo = guard.saved().draw_framebuffer;
    beginPass(gl, m, cam, opt, scaled, shared_);
    // Meshes: untextured with the pass's program, then the textured impostors
    // with theirs; those drawn behind them last, in the far depth range.
    const size_t front = std::min(n, opt.behind_from);
    if (front < n) setDepthRange(gl, 0.f, kBehindDepth);
    drawMeshes(cam, list, 0, front, opt, v, false, fs);
    drawMeshes(cam, list, 0, front, opt, v, true, fs);
    if (front < n) {
      setDepthRange(gl, kBehindDepth, 1.f);
      drawMeshes(cam, list, front, n, opt, v, false, fs);
      drawMeshes(cam, list, front, n, opt, v, true, fs);
      setDepthRange(gl, 0.f, 1.f);
    }
    if (opt.pass == Pass::Shaded) drawBackground(gl, m, cam, v, fs);
    if (scaled) stretchScaled(gl, m, out, cam, shared_, fs);
    gl.BindVertexArray(0);
    gl.BindTexture(GL_TEXTURE_2D, 0);
  }
  // The wall time must include the rasterisation, which GL defers.
  gl.Finish();
  fs.frame_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  fs.pixels = static_cast<uint64_t>(cam.width) * static_cast<uint64_t>(cam.height);
  last_w_ = out.viewport_x + out.width;
  last_h_ = out.viewport_y + out.height;
  if (stats) *stats = fs;
  // Only on a context blvd owns: on a host context this would swallow the
  // host's own pending errors.
  if (!shared_) {
    const GLenum e = gl.GetError();
    if (e == kContextLost) {
      context_lost_ = true;
      return !lost();
    }
    if (e != GL_NO_ERROR) {
      char buf[48];
      std::snprintf(buf, sizeof buf, "GL error 0x%04x in render", e);
      return fail(buf);
    }
  }
  return true;
}

bool Renderer::readPixels(uint8_t* rgba) {
  if (!rgba) return fail("readPixels: null output");
  if (lost()) return false;
  if (last_w_ == 0) return fail("readPixels: nothing rendered yet");
  if (!ctx_.makeCurrent()) return fail("GL context is not current on this thread");
  const GlApi& gl = *gl_;
  {
    ScopedGlState guard(gl, shared_);
    gl.BindFramebuffer(GL_READ_FRAMEBUFFER,
                       static_cast<GLuint>(shared_ ? impl_->host_fbo : impl_->fbo));
    if (shared_) {
      // A bound pack buffer would redirect the read into it.
      gl.BindBuffer(GL_PIXEL_PACK_BUFFER, 0);
      gl.PixelStorei(GL_PACK_ROW_LENGTH, 0);
      gl.PixelStorei(GL_PACK_SKIP_ROWS, 0);
      gl.PixelStorei(GL_PACK_SKIP_PIXELS, 0);
    }
    gl.PixelStorei(GL_PACK_ALIGNMENT, 4);
    gl.ReadPixels(0, 0, last_w_, last_h_, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
  }
  // GL's first row is the bottom one; swap rows in place (no scratch buffer).
  const size_t row = static_cast<size_t>(last_w_) * 4;
  for (int y = 0; y < last_h_ / 2; ++y) {
    uint8_t* a = rgba + static_cast<size_t>(y) * row;
    uint8_t* b = rgba + static_cast<size_t>(last_h_ - 1 - y) * row;
    std::swap_ranges(a, a + row, b);
  }
  return true;
}

}  // namespace blvd::render
