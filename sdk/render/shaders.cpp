// Shader sources. Lighting is done in linear light: vertex colours are sRGB,
// decoded with a 2.2 power (per vertex) and encoded back with gamma 2 (per pixel, see toDisplay; the exact
// piecewise curve is not worth its cost on llvmpipe). Fog is squared
// exponential so the near city stays crisp and the far city fades into the
// horizon colour, which is also where the sky gradient starts: the seam at the
// far plane and at the horizon disappears.
#include "render/shaders.h"

namespace blvd::render::shaders {

const char* const kVersionEs = "#version 300 es\n";
const char* const kVersionCore = "#version 330 core\n";

const char* const kPrelude = R"(
precision highp float;
uniform vec3 u_sun_dir;        // unit vector towards the sun, glTF axes
uniform vec3 u_sun_color;      // linear
uniform vec3 u_sky_ambient;    // linear, light from above
uniform vec3 u_ground_ambient; // linear, light bounced from below
uniform vec3 u_horizon;        // linear, also the fog colour
uniform float u_inv_fog2;      // 1 / fog_distance^2

vec3 fogged(vec3 c, float dist) {
  float f = 1.0 - exp(-dist * dist * u_inv_fog2);
  return mix(c, u_horizon, f);
}
// Gamma 2 rather than 2.2: a square root per channel instead of pow()
// (log2 + exp2) is a third of llvmpipe's per-pixel cost at street level,
// where every pixel is shaded once and the frame is fill-bound.
vec3 toDisplay(vec3 linear_rgb) {
  return sqrt(clamp(linear_rgb, 0.0, 1.0));
}
)";

const char* const kBackgroundVs = R"(
uniform mat3 u_ray_basis;  // columns: right * tan * aspect, up * tan, forward
out vec3 v_ray;
void main() {
  // Vertices 0, 1, 2 -> (-1,-1), (3,-1), (-1,3): one triangle covers the
  // viewport without the diagonal seam of a quad.
  vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
  // z = w puts it on the far plane, so it also lays down depth 1.0 and no
  // depth clear (with its host-owned clear value) is needed.
  gl_Position = vec4(p, 1.0, 1.0);
  v_ray = u_ray_basis * vec3(p, 1.0);
}
)";

const char* const kBackgroundFs = R"(
uniform vec3 u_zenith;        // linear
uniform vec3 u_ground;        // linear albedo
uniform float u_eye_height;   // metres above y = 0
in vec3 v_ray;
layout(location = 0) out vec4 o_color;
void main() {
  vec3 d = normalize(v_ray);
  vec3 c;
  if (d.y < 0.0 && u_eye_height > 0.0) {
    float dist = u_eye_height / -d.y;
    vec3 lit = u_ground * (u_sky_ambient + u_sun_color * max(u_sun_dir.y, 0.0));
    c = fogged(lit, dist);
  } else {
    // Square root: the pale band hugs the horizon, most of the sky is blue.
    c = mix(u_horizon, u_zenith, sqrt(clamp(d.y, 0.0, 1.0)));
  }
  o_color = vec4(toDisplay(c), 1.0);
}
)";

const char* const kMeshVs = R"(
layout(location = 0) in vec3 a_position;  // relative to the mesh's box centre
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec4 a_color;     // sRGB, normalised bytes
uniform mat4 u_viewproj;                  // eye-relative
uniform vec3 u_offset;                    // box centre - eye, from doubles
out vec3 v_rel;
out vec3 v_lit;
void main() {
  vec3 p = a_position + u_offset;
  v_rel = p;
  vec3 n = normalize(a_normal);
  vec3 albedo = pow(a_color.rgb, vec3(2.2));
  vec3 ambient = mix(u_ground_ambient, u_sky_ambient, n.y * 0.5 + 0.5);
  v_lit = albedo * (ambient + u_sun_color * max(dot(n, u_sun_dir), 0.0));
  gl_Position = u_viewproj * vec4(p, 1.0);
}
)";

const char* const kMeshFs = R"(
in vec3 v_rel;
in vec3 v_lit;
layout(location = 0) out vec4 o_color;
void main() {
  // Per fragment: street ribbons are long triangles, a per-vertex distance
  // would fog their middle wrongly.
  o_color = vec4(toDisplay(fogged(v_lit, length(v_rel))), 1.0);
}
)";

// ---- bake capture passes (S97 §4.2, D99 §5.3) --------------------------------
// Culling is off in these passes: the underside of anything (the paper's
// "bottom face of ground elements") must still occlude, and is marked so the
// external contour can leave it out.

const char* const kItemFs = R"(
uniform vec4 u_item;  // the object's id as a colour (item buffer)
layout(location = 0) out vec4 o_color;
void main() { o_color = u_item; }
)";

const char* const kCaptureColorFs = R"(
in vec3 v_rel;
in vec3 v_lit;
layout(location = 0) out vec4 o_color;
void main() {
  // No fog: the runtime fogs the impostor by the distance it is seen from.
  // Alpha 1 marks geometry, 0.5 the underside ("special colour"), 0 nothing.
  if (gl_FrontFacing) o_color = vec4(toDisplay(v_lit), 1.0);
  else o_color = vec4(1.0, 0.0, 1.0, 0.5);
}
)";

const char* const kCaptureDepthFs = R"(
precision highp int;
in vec3 v_rel;
in vec3 v_lit;
uniform vec3 u_forward;     // unit view direction, world axes
uniform float u_depth_scale;  // (2^24 - 1) / max depth
layout(location = 0) out vec4 o_color;
void main() {
  // View depth packed in 24 bits of RGB: GLES 3.0 cannot read back the depth
  // buffer, and float colour buffers are an extension.
  float z = max(dot(v_rel, u_forward), 0.0);
  uint q = uint(clamp(z * u_depth_scale, 1.0, 16777215.0));
  o_color = vec4(float((q >> 16) & 255u), float((q >> 8) & 255u), float(q & 255u), 255.0) / 255.0;
}
)";

// ---- textured depth meshes (impostors) ----------------------------------------

const char* const kTexturedVs = R"(
layout(location = 0) in vec3 a_position;
layout(location = 3) in vec2 a_uv;
uniform mat4 u_viewproj;
uniform vec3 u_offset;
uniform vec2 u_uv_scale;   // image size over the texture's (a slab's atlas holds many images)
uniform vec2 u_uv_offset;  // the image's corner in the texture
out vec3 v_rel;
out vec2 v_uv;
void main() {
  vec3 p = a_position + u_offset;
  v_rel = p;
  v_uv = u_uv_offset + a_uv * u_uv_scale;
  gl_Position = u_viewproj * vec4(p, 1.0);
}
)";

const char* const kTexturedFs = R"(
uniform sampler2D u_texture;  // lit colour captured at bake time (sRGB)
in vec3 v_rel;
in vec2 v_uv;
layout(location = 0) out vec4 o_color;
void main() {
  vec3 t = texture(u_texture, v_uv).rgb;
  vec3 c = t * t;  // display -> linear, the inverse of toDisplay
  o_color = vec4(toDisplay(fogged(c, length(v_rel))), 1.0);
}
)";

// The render scale's upscale (docs/decisions/0008 §7): the view drawn at
// fewer pixels into the lower-left of the scaled target's colour texture,
// stretched over the real viewport with bilinear filtering. On llvmpipe this
// pass is cheaper than a linear glBlitFramebuffer of the same size.
const char* const kUpscaleVs = R"(
uniform vec2 u_uv_scale;  // the drawn part of the texture, in texture units
out vec2 v_uv;
void main() {
  vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
  gl_Position = vec4(p, 0.0, 1.0);
  v_uv = (p * 0.5 + 0.5) * u_uv_scale;
}
)";

const char* const kUpscaleFs = R"(
uniform sampler2D u_texture;
uniform vec4 u_uv_clamp;  // texel centres at the drawn part's edges: no bleed from outside it
in vec2 v_uv;
layout(location = 0) out vec4 o_color;
void main() {
  o_color = texture(u_texture, clamp(v_uv, u_uv_clamp.xy, u_uv_clamp.zw));
}
)";

}  // namespace blvd::render::shaders
