// Capture and restore of GlStateSnapshot. Order matters on restore: the VAO
// goes back before the element buffer (that binding lives in the VAO), and
// the framebuffers before the viewport so nothing depends on a foreign target.
#include "render/gl_state.h"

namespace blvd::render {

namespace {

void setEnabled(const GlApi& gl, GLenum cap, GLboolean on) {
  if (on) {
    gl.Enable(cap);
  } else {
    gl.Disable(cap);
  }
}

}  // namespace

void GlStateSnapshot::capture(const GlApi& gl) {
  gl.GetIntegerv(GL_CURRENT_PROGRAM, &program);
  gl.GetIntegerv(GL_VERTEX_ARRAY_BINDING, &vertex_array);
  gl.GetIntegerv(GL_ARRAY_BUFFER_BINDING, &array_buffer);
  gl.GetIntegerv(GL_ELEMENT_ARRAY_BUFFER_BINDING, &element_buffer);
  gl.GetIntegerv(GL_PIXEL_PACK_BUFFER_BINDING, &pixel_pack_buffer);
  gl.GetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &draw_framebuffer);
  gl.GetIntegerv(GL_READ_FRAMEBUFFER_BINDING, &read_framebuffer);
  gl.GetIntegerv(GL_RENDERBUFFER_BINDING, &renderbuffer);
  gl.GetIntegerv(GL_VIEWPORT, viewport);
  gl.GetIntegerv(GL_SCISSOR_BOX, scissor_box);
  gl.GetIntegerv(GL_PIXEL_UNPACK_BUFFER_BINDING, &pixel_unpack_buffer);
  gl.GetIntegerv(GL_COPY_READ_BUFFER_BINDING, &copy_read_buffer);
  gl.GetIntegerv(GL_COPY_WRITE_BUFFER_BINDING, &copy_write_buffer);
  gl.GetIntegerv(GL_UNPACK_ALIGNMENT, &unpack_alignment);
  gl.GetIntegerv(GL_UNPACK_ROW_LENGTH, &unpack_row_length);
  gl.GetIntegerv(GL_ACTIVE_TEXTURE, &active_texture);
  // Impostors sample unit 0: remember what the host had bound there.
  gl.ActiveTexture(GL_TEXTURE0);
  gl.GetIntegerv(GL_TEXTURE_BINDING_2D, &texture0_2d);
  gl.ActiveTexture(static_cast<GLenum>(active_texture));
  gl.GetFloatv(GL_COLOR_CLEAR_VALUE, clear_color);
  gl.GetFloatv(GL_DEPTH_CLEAR_VALUE, &clear_depth);
  gl.GetFloatv(GL_DEPTH_RANGE, depth_range);
  gl.GetIntegerv(GL_DEPTH_FUNC, &depth_func);
  gl.GetIntegerv(GL_CULL_FACE_MODE, &cull_face_mode);
  gl.GetIntegerv(GL_FRONT_FACE, &front_face);
  gl.GetIntegerv(GL_PACK_ALIGNMENT, &pack_alignment);
  gl.GetIntegerv(GL_PACK_ROW_LENGTH, &pack_row_length);
  gl.GetIntegerv(GL_PACK_SKIP_ROWS, &pack_skip_rows);
  gl.GetIntegerv(GL_PACK_SKIP_PIXELS, &pack_skip_pixels);
  depth_test = gl.IsEnabled(GL_DEPTH_TEST);
  gl.GetBooleanv(GL_DEPTH_WRITEMASK, &depth_mask);
  cull_face = gl.IsEnabled(GL_CULL_FACE);
  blend = gl.IsEnabled(GL_BLEND);
  polygon_offset_fill = gl.IsEnabled(GL_POLYGON_OFFSET_FILL);
  scissor_test = gl.IsEnabled(GL_SCISSOR_TEST);
  stencil_test = gl.IsEnabled(GL_STENCIL_TEST);
  rasterizer_discard = gl.IsEnabled(GL_RASTERIZER_DISCARD);
  gl.GetBooleanv(GL_COLOR_WRITEMASK, color_mask);
}

void GlStateSnapshot::restore(const GlApi& gl) const {
  gl.UseProgram(static_cast<GLuint>(program));
  gl.BindVertexArray(static_cast<GLuint>(vertex_array));
  gl.BindBuffer(GL_ARRAY_BUFFER, static_cast<GLuint>(array_buffer));
  gl.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLuint>(element_buffer));
  gl.BindBuffer(GL_PIXEL_PACK_BUFFER, static_cast<GLuint>(pixel_pack_buffer));
  gl.BindFramebuffer(GL_DRAW_FRAMEBUFFER, static_cast<GLuint>(draw_framebuffer));
  gl.BindFramebuffer(GL_READ_FRAMEBUFFER, static_cast<GLuint>(read_framebuffer));
  gl.BindRenderbuffer(GL_RENDERBUFFER, static_cast<GLuint>(renderbuffer));
  gl.Viewport(viewport[0], viewport[1], viewport[2], viewport[3]);
  gl.Scissor(scissor_box[0], scissor_box[1], scissor_box[2], scissor_box[3]);
  gl.BindBuffer(GL_PIXEL_UNPACK_BUFFER, static_cast<GLuint>(pixel_unpack_buffer));
  gl.BindBuffer(GL_COPY_READ_BUFFER, static_cast<GLuint>(copy_read_buffer));
  gl.BindBuffer(GL_COPY_WRITE_BUFFER, static_cast<GLuint>(copy_write_buffer));
  gl.PixelStorei(GL_UNPACK_ALIGNMENT, unpack_alignment);
  gl.PixelStorei(GL_UNPACK_ROW_LENGTH, unpack_row_length);
  gl.ActiveTexture(GL_TEXTURE0);
  gl.BindTexture(GL_TEXTURE_2D, static_cast<GLuint>(texture0_2d));
  gl.ActiveTexture(static_cast<GLenum>(active_texture));
  gl.ClearColor(clear_color[0], clear_color[1], clear_color[2], clear_color[3]);
  if (gl.ClearDepthf) gl.ClearDepthf(clear_depth);
  if (gl.DepthRangef) gl.DepthRangef(depth_range[0], depth_range[1]);
  else if (gl.DepthRange) gl.DepthRange(depth_range[0], depth_range[1]);
  gl.DepthFunc(static_cast<GLenum>(depth_func));
  gl.CullFace(static_cast<GLenum>(cull_face_mode));
  gl.FrontFace(static_cast<GLenum>(front_face));
  gl.PixelStorei(GL_PACK_ALIGNMENT, pack_alignment);
  gl.PixelStorei(GL_PACK_ROW_LENGTH, pack_row_length);
  gl.PixelStorei(GL_PACK_SKIP_ROWS, pack_skip_rows);
  gl.PixelStorei(GL_PACK_SKIP_PIXELS, pack_skip_pixels);
  setEnabled(gl, GL_DEPTH_TEST, depth_test);
  gl.DepthMask(depth_mask);
  setEnabled(gl, GL_CULL_FACE, cull_face);
  setEnabled(gl, GL_BLEND, blend);
  setEnabled(gl, GL_POLYGON_OFFSET_FILL, polygon_offset_fill);
  setEnabled(gl, GL_SCISSOR_TEST, scissor_test);
  setEnabled(gl, GL_STENCIL_TEST, stencil_test);
  setEnabled(gl, GL_RASTERIZER_DISCARD, rasterizer_discard);
  gl.ColorMask(color_mask[0], color_mask[1], color_mask[2], color_mask[3]);
}

}  // namespace blvd::render
