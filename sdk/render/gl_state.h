// Save and restore of the GL state the renderer touches, for contexts the host
// owns (Backend::Shared): after any renderer call the host finds its program,
// bindings, viewport and fixed-function switches as it left them.
//
// Covered: program, VAO, array/element/pixel-pack buffers, draw/read
// framebuffers, renderbuffer, viewport, scissor box, pixel-unpack buffer and
// unpack alignment/row length, active texture, depth test/func/mask/range,
// cull face/mode, front face, blend, polygon offset fill, scissor test,
// stencil test, rasterizer discard, colour mask, pack alignment/row
// length/skips, clear colour and depth, texture unit 0's 2D binding. Not
// covered (never touched): blend equation, other textures and samplers,
// uniform buffers.
#pragma once
#include "render/gl_api.h"

namespace blvd::render {

struct GlStateSnapshot {
  GLint program, vertex_array, array_buffer, element_buffer, pixel_pack_buffer;
  GLint draw_framebuffer, read_framebuffer, renderbuffer;
  GLint viewport[4], scissor_box[4];
  GLint pixel_unpack_buffer, unpack_alignment, unpack_row_length;
  GLint copy_read_buffer, copy_write_buffer;  // slab copies (Renderer::beginSlabCopy)
  GLint active_texture, texture0_2d, depth_func, cull_face_mode, front_face;
  GLfloat clear_color[4];
  GLfloat clear_depth;
  GLfloat depth_range[2];
  GLint pack_alignment, pack_row_length, pack_skip_rows, pack_skip_pixels;
  GLboolean depth_test, depth_mask, cull_face, blend, polygon_offset_fill, scissor_test,
      stencil_test, rasterizer_discard;
  GLboolean color_mask[4];

  void capture(const GlApi& gl);
  void restore(const GlApi& gl) const;
};

// Captures on construction and restores on destruction when `active`; an
// inactive guard costs nothing (a context blvd owns has no state to protect).
class ScopedGlState {
 public:
  ScopedGlState(const GlApi& gl, bool active) : gl_(gl), active_(active) {
    if (active_) saved_.capture(gl_);
  }
  ~ScopedGlState() {
    if (active_) saved_.restore(gl_);
  }
  ScopedGlState(const ScopedGlState&) = delete;
  ScopedGlState& operator=(const ScopedGlState&) = delete;
  const GlStateSnapshot& saved() const { return saved_; }

 private:
  const GlApi& gl_;
  bool active_;
  GlStateSnapshot saved_{};
};

}  // namespace blvd::render
