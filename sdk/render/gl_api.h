// The GL entry points the renderer uses, as a table of function pointers
// loaded through Context::getProcAddress. Nothing links libGL/libGLESv2, so the
// same renderer runs on EGL (GLES 3.x), OSMesa (desktop GL 3.3+) or a host's
// context. Only the common subset of GLES 3.0 and GL 3.3 core is listed.
#pragma once
// Types, enums and PFN typedefs from the GLES 3.0 header, without prototypes:
// a call that bypasses the table would not link, which is the point.
#ifndef GL_GLES_PROTOTYPES
#define GL_GLES_PROTOTYPES 0
#endif
#include <GLES3/gl3.h>

#include <string>

namespace blvd::render {

class Context;

// X(PFN type, member name, GL name without the "gl" prefix)
#define BLVD_GL_FUNCTIONS(X)                                   \
  X(PFNGLACTIVETEXTUREPROC, ActiveTexture)                     \
  X(PFNGLATTACHSHADERPROC, AttachShader)                       \
  X(PFNGLBINDBUFFERPROC, BindBuffer)                           \
  X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer)                 \
  X(PFNGLBINDRENDERBUFFERPROC, BindRenderbuffer)               \
  X(PFNGLBINDTEXTUREPROC, BindTexture)                         \
  X(PFNGLBINDVERTEXARRAYPROC, BindVertexArray)                 \
  X(PFNGLBLITFRAMEBUFFERPROC, BlitFramebuffer)                 \
  X(PFNGLBLENDFUNCPROC, BlendFunc)                             \
  X(PFNGLBUFFERDATAPROC, BufferData)                           \
  X(PFNGLBUFFERSUBDATAPROC, BufferSubData)                     \
  X(PFNGLCOPYBUFFERSUBDATAPROC, CopyBufferSubData)             \
  X(PFNGLCHECKFRAMEBUFFERSTATUSPROC, CheckFramebufferStatus)   \
  X(PFNGLCLEARPROC, Clear)                                     \
  X(PFNGLCLEARCOLORPROC, ClearColor)                           \
  X(PFNGLCOLORMASKPROC, ColorMask)                             \
  X(PFNGLCOMPILESHADERPROC, CompileShader)                     \
  X(PFNGLCREATEPROGRAMPROC, CreateProgram)                     \
  X(PFNGLCREATESHADERPROC, CreateShader)                       \
  X(PFNGLCULLFACEPROC, CullFace)                               \
  X(PFNGLDELETEBUFFERSPROC, DeleteBuffers)                     \
  X(PFNGLDELETEFRAMEBUFFERSPROC, DeleteFramebuffers)           \
  X(PFNGLDELETEPROGRAMPROC, DeleteProgram)                     \
  X(PFNGLDELETERENDERBUFFERSPROC, DeleteRenderbuffers)         \
  X(PFNGLDELETESHADERPROC, DeleteShader)                       \
  X(PFNGLDELETETEXTURESPROC, DeleteTextures)                   \
  X(PFNGLDELETEVERTEXARRAYSPROC, DeleteVertexArrays)           \
  X(PFNGLDEPTHFUNCPROC, DepthFunc)                             \
  X(PFNGLDEPTHMASKPROC, DepthMask)                             \
  X(PFNGLDISABLEPROC, Disable)                                 \
  X(PFNGLDRAWARRAYSPROC, DrawArrays)                           \
  X(PFNGLDRAWELEMENTSPROC, DrawElements)                       \
  X(PFNGLENABLEPROC, Enable)                                   \
  X(PFNGLENABLEVERTEXATTRIBARRAYPROC, EnableVertexAttribArray) \
  X(PFNGLFINISHPROC, Finish)                                   \
  X(PFNGLFLUSHPROC, Flush)                                     \
  X(PFNGLFRAMEBUFFERRENDERBUFFERPROC, FramebufferRenderbuffer) \
  X(PFNGLFRAMEBUFFERTEXTURE2DPROC, FramebufferTexture2D)       \
  X(PFNGLFRONTFACEPROC, FrontFace)                             \
  X(PFNGLGENBUFFERSPROC, GenBuffers)                           \
  X(PFNGLGENFRAMEBUFFERSPROC, GenFramebuffers)                 \
  X(PFNGLGENRENDERBUFFERSPROC, GenRenderbuffers)               \
  X(PFNGLGENTEXTURESPROC, GenTextures)                         \
  X(PFNGLGENERATEMIPMAPPROC, GenerateMipmap)                   \
  X(PFNGLGENVERTEXARRAYSPROC, GenVertexArrays)                 \
  X(PFNGLGETBOOLEANVPROC, GetBooleanv)                         \
  X(PFNGLGETBUFFERPARAMETERI64VPROC, GetBufferParameteri64v)   \
  X(PFNGLGETERRORPROC, GetError)                               \
  X(PFNGLGETFLOATVPROC, GetFloatv)                             \
  X(PFNGLGETINTEGERVPROC, GetIntegerv)                         \
  X(PFNGLGETPROGRAMINFOLOGPROC, GetProgramInfoLog)             \
  X(PFNGLGETPROGRAMIVPROC, GetProgramiv)                       \
  X(PFNGLGETSHADERINFOLOGPROC, GetShaderInfoLog)               \
  X(PFNGLGETSHADERIVPROC, GetShaderiv)                         \
  X(PFNGLGETSTRINGPROC, GetString)                             \
  X(PFNGLGETUNIFORMLOCATIONPROC, GetUniformLocation)           \
  X(PFNGLISENABLEDPROC, IsEnabled)                             \
  X(PFNGLLINKPROGRAMPROC, LinkProgram)                         \
  X(PFNGLPIXELSTOREIPROC, PixelStorei)                         \
  X(PFNGLPOLYGONOFFSETPROC, PolygonOffset)                     \
  X(PFNGLREADPIXELSPROC, ReadPixels)                           \
  X(PFNGLRENDERBUFFERSTORAGEPROC, RenderbufferStorage)         \
  X(PFNGLSCISSORPROC, Scissor)                                 \
  X(PFNGLSHADERSOURCEPROC, ShaderSource)                       \
  X(PFNGLTEXIMAGE2DPROC, TexImage2D)                           \
  X(PFNGLTEXPARAMETERIPROC, TexParameteri)                     \
  X(PFNGLTEXSUBIMAGE2DPROC, TexSubImage2D)                     \
  X(PFNGLUNIFORM1FPROC, Uniform1f)                             \
  X(PFNGLUNIFORM1IPROC, Uniform1i)                             \
  X(PFNGLUNIFORM2FPROC, Uniform2f)                             \
  X(PFNGLUNIFORM3FPROC, Uniform3f)                             \
  X(PFNGLUNIFORM4FPROC, Uniform4f)                             \
  X(PFNGLUNIFORMMATRIX3FVPROC, UniformMatrix3fv)               \
  X(PFNGLUNIFORMMATRIX4FVPROC, UniformMatrix4fv)               \
  X(PFNGLUSEPROGRAMPROC, UseProgram)                           \
  X(PFNGLVERTEXATTRIBPOINTERPROC, VertexAttribPointer)         \
  X(PFNGLVIEWPORTPROC, Viewport)

struct GlApi {
#define BLVD_GL_MEMBER(type, name) type name = nullptr;
  BLVD_GL_FUNCTIONS(BLVD_GL_MEMBER)
#undef BLVD_GL_MEMBER

  // Optional: GLES 3 and GL 4.1 have it, a GL 3.3 host context may not.
  PFNGLCLEARDEPTHFPROC ClearDepthf = nullptr;
  // One of the two: GLES 3 and GL 4.1 have glDepthRangef, GL 3.3 glDepthRange.
  PFNGLDEPTHRANGEFPROC DepthRangef = nullptr;
  void(GL_APIENTRYP DepthRange)(double near_d, double far_d) = nullptr;
  // Optional: desktop GL and GLES 3.1 have it, GLES 3.0 does not (what the
  // driver allocated for each texture level: Renderer::measuredSlabBytes).
  void(GL_APIENTRYP GetTexLevelParameteriv)(GLenum target, GLint level, GLenum pname, GLint* params) = nullptr;
  // Optional: an ETC2 slab atlas's (GLES 3.0 and GL 4.3 have both; the
  // renderer checks the version, since EGL may name what a context lacks).
  PFNGLTEXSTORAGE2DPROC TexStorage2D = nullptr;
  PFNGLCOMPRESSEDTEXSUBIMAGE2DPROC CompressedTexSubImage2D = nullptr;

  // Loads every entry point through ctx.getProcAddress (ctx must be current).
  // False when any is missing; `missing` then lists them, e.g.
  // "glGenVertexArrays glBufferSubData".
  bool load(Context& ctx, std::string& missing);
};

}  // namespace blvd::render
