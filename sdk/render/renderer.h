// The street-level renderer: uploads meshes once, then per frame draws the
// sky and ground background, frustum-culls the caller's draw list by each
// mesh's bounding box and draws what survives, lit by a sun and a sky.
//
// Thread: every call on the thread where the context is current.
// Lifetime: the Renderer borrows the Context; destroy the Renderer first.
// Memory: the mesh pool is sized once from RendererDesc; render() and
// readPixels() make no heap allocations (upload() reuses its scratch buffers).
// Errors: calls return false / an invalid handle and set lastError().
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "geo/mesh.h"
#include "render/camera.h"
#include "render/prepared_mesh.h"
#include "render/slab_atlas.h"

namespace blvd::render {

class Context;
struct GlApi;

struct RendererDesc {
  int width = 0;                // own framebuffer size; 0 means 800. Unused when shared
  int height = 0;               // 0 means 480
  uint32_t mesh_capacity = 0;   // live meshes at once; 0 means 16384, at most 2^20 - 1
  // Also create a reduced-resolution target (RGBA8 + depth24 of width x
  // height, required then even when shared) so that RenderOptions::scale < 1
  // can draw fewer pixels and stretch them over the view: the frame-time
  // budget's second knob on a fill-bound GPU (docs/decisions/0008).
  bool scaled_target = false;
};

// `desc` with every zero field replaced by its default.
RendererDesc rendererDescDefaults(const RendererDesc& desc);

// Lighting and atmosphere. Colours are sRGB 0..1.
struct Look {
  double sun_elevation_deg = 50.0;
  double sun_azimuth_deg = 200.0;  // clockwise from north
  float fog_distance_m = 0.0f;     // e-folding distance of the squared fog; 0 means 0.4 * far
  float sky_zenith[3] = {0.30f, 0.50f, 0.80f};
  float sky_horizon[3] = {0.80f, 0.85f, 0.90f};  // also the fog colour
  float ground[3] = {0.45f, 0.48f, 0.40f};       // grey-green
};

// Typed handle from a pool: 20-bit slot index + 1 and a 12-bit generation, so
// a released handle stays invalid after its slot is reused. id 0 is invalid.
struct MeshHandle {
  uint32_t id = 0;
  bool operator==(const MeshHandle& o) const { return id == o.id; }
  bool operator!=(const MeshHandle& o) const { return id != o.id; }
};

// A fixed GPU arena: one vertex buffer, one index buffer, `meshes`
// vertex arrays and one RGBA8 texture of atlas_width × atlas_height with
// kAtlasLevels mip levels (slab_atlas.h), all allocated by createSlab. Meshes
// are then placed into it in order with uploadToSlab (glBufferSubData /
// glTexSubImage2D only: no GL allocation), each textured one's image at the
// place its PreparedMesh names, and released together by resetSlab.
struct SlabDesc {
  uint64_t vertex_bytes = 0;
  uint64_t index_bytes = 0;  // 4-byte aligned placements; budget 3 bytes per mesh for it
  uint32_t meshes = 0;
  int atlas_width = 0, atlas_height = 0;  // multiples of atlasAlign(atlas_format); 0: no texture
  AtlasFormat atlas_format = AtlasFormat::Rgba8;  // Etc2: images need PreparedMesh::etc2 (atlas_etc2.h)
};
struct SlabHandle {
  uint32_t id = 0;  // index + 1; 0 is invalid
};

// A mesh copied into a slab over several calls, so that a frame's uploads
// stay within its time budget: beginSlabUpload reserves the mesh's
// bytes and texture in the slab, continueSlabUpload copies the vertices, the
// indices and the texture's mip levels (whole rows) a chunk at a time. The
// PreparedMesh must stay valid until the upload finishes; resetSlab abandons
// an unfinished one.
//
// beginSlabCopy starts the same for a mesh already in another slab: the
// bytes move GPU-side (glCopyBufferSubData); `mesh` is null and `shape`
// holds the source's counts and box (no CPU pointers).
struct SlabUpload {
  uint32_t slab = 0;                  // SlabHandle id; 0 when idle
  const PreparedMesh* mesh = nullptr;
  uint32_t source = 0;                // a copy: the source mesh's handle id; 0 for an upload
  uint32_t source_resets = 0;         // and its slab's reset count at begin
  PreparedMesh shape;                 // a copy: the source's counts, index type and box
  uint64_t voff = 0, ioff = 0;        // placement in the slab's buffers
  uint32_t texture = 0;               // the slab's atlas (GL name) for a textured mesh, else 0
  uint64_t copied = 0, total = 0;     // bytes, in the order vertices, indices, texture levels
  uint32_t resets = 0;                // the slab's reset count at begin
};
struct SlabUsage {
  uint64_t vertex_bytes = 0, index_bytes = 0;
  uint32_t meshes = 0, textures = 0;
  uint64_t texture_bytes = 0;  // the atlas's texels the images' places take, every level
};
// GPU bytes a slab holds: buffers plus the atlas with its levels.
uint64_t slabGpuBytes(const SlabDesc& desc);

struct FrameStats {
  double frame_ms = 0.0;        // render() wall time, glFinish included
  uint64_t triangles = 0;       // triangles of the meshes drawn (background excluded)
  uint32_t draw_calls = 0;      // every glDraw* issued, the background's included
  uint32_t meshes_drawn = 0;
  uint32_t meshes_culled = 0;   // outside the view frustum
  uint32_t parts_culled = 0;    // parts of drawn meshes outside it (MeshPart)
  uint32_t meshes_invalid = 0;  // stale or null handles in the list, skipped
  uint64_t pixels = 0;          // pixels shaded: the view's, or the scaled view's
};

// What a render() call draws. Shaded is the street view. The capture passes
// serve the bake (S97 §4.2, D99 §5.3): they clear to transparent black, draw
// no sky or ground, and turn back-face culling off so undersides occlude.
enum class Pass {
  Shaded,        // sky + ground background, lit and fogged meshes, textured impostors
  ItemBuffer,    // each mesh in the flat colour of its id (RGB = 24-bit id, A = 255)
  CaptureColor,  // lit colour without fog; A = 255 geometry, 128 an underside, 0 nothing
  CaptureDepth,  // view depth packed as 24-bit RGB fixed point over [0, max_depth_m]; 0 = nothing
};

struct RenderOptions {
  Pass pass = Pass::Shaded;
  const uint32_t* item_ids = nullptr;  // ItemBuffer: one id per list entry (ids < 2^24, 0 = nothing)
  double max_depth_m = 8192.0;         // CaptureDepth scale
  // Shaded pass only, with RendererDesc::scaled_target: draw the view at
  // round(scale x size) pixels into the scaled target, then blit it over the
  // view with linear filtering. Only colour reaches the destination (a host's
  // depth buffer is left as it was). 1 draws at full size; (0, 1].
  double scale = 1.0;
  // The list's entries from this index on (the terrain) are drawn behind all
  // before it, whatever their depths: in the far part of the depth range
  // (kBehindDepth..1), the others in the near part, so that they show only
  // where the others drew nothing and still hide one another. SIZE_MAX: none.
  size_t behind_from = SIZE_MAX;
  // ItemBuffer only: clear the colour but keep the depth the last render()
  // left, and test against it (less or equal): a second set of items (lines)
  // drawn where the first's surfaces do not hide them, the nearest winning.
  bool keep_depth = false;
};
// Where the depth range is split when a list has entries drawn behind.
inline constexpr float kBehindDepth = 0.75f;

// Unpacks a CaptureDepth pixel to metres (0 where nothing was drawn).
inline double unpackCaptureDepth(const uint8_t* rgba, double max_depth_m) {
  const uint32_t q = (uint32_t(rgba[0]) << 16) | (uint32_t(rgba[1]) << 8) | rgba[2];
  return q == 0 ? 0.0 : double(q) * max_depth_m / 16777215.0;
}

struct FrameView;  // renderer.cpp

class Renderer {
 public:
  // Loads GL through `ctx` (made current here), compiles the shaders and, for
  // a context blvd owns, creates the RGBA8 + depth24 framebuffer. nullptr with
  // `err` set on failure (missing GL entry points, GL older than ES 3.0 / 3.3,
  // shader or framebuffer errors).
  static std::unique_ptr<Renderer> create(Context& ctx, const RendererDesc& desc,
                                          std::string& err);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Copies `mesh` to GL buffers. Missing normals are computed from the
  // triangles, missing colours default to light grey. A mesh with texcoords
  // and an embedded image (PNG/JPEG) is drawn textured and unlit (its colour
  // was lit when it was captured): the impostors. Invalid handle when the
  // mesh is empty or malformed (index out of range, array sizes disagree) or
  // the pool is full.
  MeshHandle upload(const geo::MeshData& mesh);
  // Copies line segments (`mesh.indices` in pairs; prepareLines), drawn as
  // GL_LINES, one pixel wide, by every pass: a line marks each pixel it
  // crosses however thin its subject (the bake's conservative item buffer).
  MeshHandle uploadLines(const geo::MeshData& mesh);
  // Raises the mesh pool's capacity by `more` (outside a frame: it may
  // allocate), for meshes a mode needs only when chosen (the runtime's
  // reference modes hold every block). False past 2^20 - 1 meshes.
  bool reserveMeshes(uint32_t more);
  // Frees the GL buffers; stale and null handles are ignored. A slab mesh
  // gives its handle back; its bytes stay with the slab until resetSlab.
  void release(MeshHandle h);

  // Creates a slab (see SlabDesc). Call at start-up: this is where GL
  // allocates. Invalid handle with lastError() set on failure; outOfMemory()
  // then says whether the driver ran out of memory (GL_OUT_OF_MEMORY).
  SlabHandle createSlab(const SlabDesc& desc);
  bool outOfMemory() const;
  // The driver reported GL_CONTEXT_LOST after a frame (a GPU reset; GLES 3.2,
  // KHR_robustness): the context's objects are gone, so every later call
  // fails at once with the same error and touches no GL. The owner destroys
  // the renderer (its runtime) and creates a new one.
  bool contextLost() const { return context_lost_; }
  // Places a prepared mesh after the slab's last one, its image (if any) at
  // (atlas_x, atlas_y) of the slab's atlas. Invalid handle when the slab or
  // the mesh pool is full, or the image's place is outside the atlas, not on
  // its kAtlasAlign grid or overlaps an image already there. The only GL calls
  // are sub-data copies.
  MeshHandle uploadToSlab(SlabHandle slab, const PreparedMesh& mesh);
  // The same in steps (see SlabUpload). begin: false with lastError() set
  // when the slab or the mesh pool has no room. continueSlabUpload copies at
  // least one chunk (a texture row, or all that is left of a buffer up to
  // max_bytes) and returns the mesh's handle after the last byte; until then
  // an invalid handle with `finished` false. On failure (abandoned by
  // resetSlab, pool full) an invalid handle, `finished` true, lastError() set.
  bool beginSlabUpload(SlabHandle slab, const PreparedMesh& mesh, SlabUpload& up);
  MeshHandle continueSlabUpload(SlabUpload& up, uint64_t max_bytes, bool& finished);
  // A slab mesh without a texture (a block level) copied into another slab,
  // GPU to GPU, then finished by continueSlabUpload like an upload: no CPU
  // copy and no GL allocation. The source's slab must not be reset before
  // the copy finishes. False with lastError() set for an invalid or textured
  // source, a mesh outside a slab, or no room.
  bool beginSlabCopy(SlabHandle slab, MeshHandle source, SlabUpload& up);
  // Releases every mesh placed in the slab and rewinds it.
  void resetSlab(SlabHandle slab);
  SlabUsage slabUsage(SlabHandle slab) const;
  uint64_t slabBytes() const { return gpu_slab_bytes_; }
  // The same bytes as the GL reports them: each slab's buffers' GL_BUFFER_SIZE
  // and each texture level's GL_TEXTURE_WIDTH x GL_TEXTURE_HEIGHT x 4 (RGBA8).
  // `textures_known` is false where the GL cannot report texture levels
  // (GLES 3.0): their bytes are then left out.
  uint64_t measuredSlabBytes(bool& textures_known);
  bool isValid(MeshHandle h) const;

  void setLook(const Look& look);
  const Look& look() const { return look_; }

  // Draws one frame of `list[0..n)` (duplicates are drawn twice) seen by
  // `cam`, into the own framebuffer or, when shared, into the framebuffer the
  // host has bound, over the viewport (0, 0, cam.width, cam.height). With an
  // own framebuffer cam.width/height must fit RendererDesc's size.
  bool render(const Camera& cam, const MeshHandle* list, size_t n, FrameStats* stats,
              const RenderOptions& options = RenderOptions());

  // Copies the last frame (lastWidth() x lastHeight()) as RGBA8, top row first.
  bool readPixels(uint8_t* rgba_top_row_first);
  // A frame of several views reads back as one: the area they share.
  void setReadSize(int w, int h) { last_w_ = w, last_h_ = h; }
  int lastWidth() const { return last_w_; }
  int lastHeight() const { return last_h_; }

  const char* backendName() const;
  const char* glRenderer() const { return gl_renderer_.c_str(); }
  const char* glVersion() const { return gl_version_.c_str(); }
  bool isGles() const { return gles_; }
  // Whether a slab's atlas may be AtlasFormat::Etc2: OpenGL ES 3.0 (whose
  // every device decodes ETC2) or OpenGL 4.3, with glTexStorage2D.
  bool supportsEtc2() const { return etc2_; }
  uint32_t meshCount() const { return live_meshes_; }
  uint64_t meshBytes() const { return mesh_bytes_; }  // vertex + index bytes in GL buffers
  const std::string& lastError() const { return error_; }
  // The GL entry points this renderer calls: a test puts a failing driver's
  // in their place (tests/render: fault injection).
  GlApi& api() { return *gl_; }

 public:
  struct Impl;  // renderer.cpp's; public so that its drawing helpers there can take it

 private:
  struct Slab;
  explicit Renderer(Context& ctx);
  const char* checkRender(const Camera& out, const MeshHandle* list, size_t n, const RenderOptions& opt) const;
  void drawMeshes(const Camera& cam, const MeshHandle* list, size_t from, size_t to, const RenderOptions& opt,
                  const FrameView& v, bool textured, FrameStats& fs);
  // upload and uploadLines: a mesh with GL buffers of its own.
  MeshHandle uploadOwn(const geo::MeshData& mesh, bool lines);
  // A mesh's slot and vertex array; copies its bytes unless `copied` (a
  // finished SlabUpload) says where they already are.
  MeshHandle place(const PreparedMesh& mesh, uint32_t slab_id, const SlabUpload* copied = nullptr);
  // Takes room for `mesh` in `slab` (no GL): its offsets, texture and byte
  // count into `up`. False with lastError() set when it has none.
  bool reserve(Slab& slab, const PreparedMesh& mesh, SlabUpload& up);
  bool placeImage(Slab& slab, const PreparedMesh& mesh);
  // An image's atlas levels into its place, from byte `begin` of the upload
  // on, within `allowance` bytes (less what they copy).
  void copyRgbaLevels(SlabUpload& up, const PreparedMesh& mesh, uint64_t begin, uint64_t& allowance);
  void copyEtc2Levels(SlabUpload& up, const PreparedMesh& mesh, uint64_t begin, uint64_t& allowance);
  bool init(const RendererDesc& desc);
  bool fail(const char* what);

  Context& ctx_;
  std::unique_ptr<GlApi> gl_;
  std::unique_ptr<Impl> impl_;
  Look look_;
  std::string gl_renderer_, gl_version_, error_;
  bool gles_ = true;
  bool etc2_ = false;
  bool shared_ = false;
  bool out_of_memory_ = false;  // the last createSlab failed with GL_OUT_OF_MEMORY
  bool context_lost_ = false;
  bool lost();  // contextLost(), with lastError() set
  int fb_w_ = 0, fb_h_ = 0;
  int last_w_ = 0, last_h_ = 0;
  uint32_t live_meshes_ = 0;
  uint64_t mesh_bytes_ = 0;
  uint64_t gpu_slab_bytes_ = 0;
};

}  // namespace blvd::render
