#include "render/prepared_mesh.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>

#include <glm/glm.hpp>
#include <stb_image.h>
#include <webp/decode.h>

#include "render/stb_alloc.h"

namespace blvd::render {
namespace {

// prepared_mesh.h's layout: the position, then 8 bytes that an untextured
// mesh fills with its normal and colour and a textured one with its uv.
struct Vertex {
  float position[3];
  uint8_t rest[8];
};
static_assert(sizeof(Vertex) == kVertexBytes, "Vertex must be tightly packed");

constexpr size_t kAlign = 16;
size_t alignUp(size_t n) { return (n + kAlign - 1) & ~(kAlign - 1); }

bool failWith(std::string& err, const char* what) {
  err = what;
  return false;
}

}  // namespace

void* StagingArena::take(size_t bytes) {
  const size_t at = alignUp(used);
  if (at > capacity || capacity - at < bytes) return nullptr;
  used = at + bytes;
  return base + at;
}

uint64_t mipChainBytes(int w, int h, int* levels) {
  uint64_t bytes = 0;
  int n = 0;
  if (w > 0 && h > 0)
    for (;; w = std::max(1, w / 2), h = std::max(1, h / 2)) {
      bytes += uint64_t(w) * uint64_t(h) * 4;
      ++n;
      if (w == 1 && h == 1) break;
    }
  if (levels) *levels = n;
  return bytes;
}

const uint8_t* mipLevel(const PreparedMesh& mesh, int level, int& w, int& h) {
  w = mesh.texture_width;
  h = mesh.texture_height;
  if (!mesh.rgba || level < 0 || level >= mesh.mip_levels) return nullptr;
  const uint8_t* p = mesh.rgba;
  for (int l = 0; l < level; ++l) {
    p += uint64_t(w) * uint64_t(h) * 4;
    w = std::max(1, w / 2);
    h = std::max(1, h / 2);
  }
  return p;
}

size_t preparedBytes(uint64_t vertices, uint64_t indices, int w, int h) {
  const uint64_t index_size = vertices < 0xFFFF ? 2 : 4;
  return alignUp(vertices * kVertexBytes) + alignUp(indices * index_size) + alignUp(mipChainBytes(w, h)) + kAlign;
}

namespace {
// One mip level from the one above: each texel the rounded mean of its 2 × 2
// parents (edge texels repeat where the parent has an odd size), as
// glGenerateMipmap's box filter does, on the encoded values.
void downsample(const uint8_t* src, int sw, int sh, uint8_t* dst, int dw, int dh) {
  for (int y = 0; y < dh; ++y)
    for (int x = 0; x < dw; ++x) {
      const int x0 = std::min(2 * x, sw - 1), x1 = std::min(2 * x + 1, sw - 1);
      const int y0 = std::min(2 * y, sh - 1), y1 = std::min(2 * y + 1, sh - 1);
      for (int c = 0; c < 4; ++c) {
        const unsigned sum = src[(size_t(y0) * sw + x0) * 4 + c] + src[(size_t(y0) * sw + x1) * 4 + c] +
                             src[(size_t(y1) * sw + x0) * 4 + c] + src[(size_t(y1) * sw + x1) * 4 + c];
        dst[(size_t(y) * dw + x) * 4 + c] = static_cast<uint8_t>((sum + 2) / 4);
      }
    }
}

// The mesh's image as RGBA8, the top of a mip chain taken from the arena:
// WebP decodes straight into it (libwebp), PNG and JPEG through stb_image.
// The type is the one the GLB decoder read from the image's bytes.
// Null with `err` set when the image cannot be decoded or does not fit.
constexpr char kNoMemory[] = "out of memory decoding the mesh's image";

// WebP straight into the arena; the decoder's own buffers are malloc'd.
VP8StatusCode webpInto(const uint8_t* d, size_t n, uint8_t* rgba, int w, int h) {
  WebPDecoderConfig config;
  if (!WebPInitDecoderConfig(&config)) return VP8_STATUS_UNSUPPORTED_FEATURE;
  config.output.colorspace = MODE_RGBA;
  config.output.is_external_memory = 1;
  config.output.u.RGBA.rgba = rgba;
  config.output.u.RGBA.stride = w * 4;
  config.output.u.RGBA.size = size_t(w) * size_t(h) * 4;
  const VP8StatusCode st = WebPDecode(d, n, &config);
  WebPFreeDecBuffer(&config.output);  // external memory: frees nothing of ours
  return st;
}

// A failed allocation must not pass for a bad image (the runtime asks for an
// out-of-memory cell again, never for a corrupt one), but libwebp reports
// some as a bitstream error: the alpha plane's decoder (an impostor's mask)
// says "could not decode alpha data" whatever failed. The decoder is
// deterministic, so an image that decodes on a second try was good: that
// failure was an allocation.
bool decodeWebp(const uint8_t* d, size_t n, uint8_t* rgba, int w, int h, std::string& err) {
  const VP8StatusCode st = webpInto(d, n, rgba, w, h);
  if (st == VP8_STATUS_OK) return true;
  if (st == VP8_STATUS_OUT_OF_MEMORY || webpInto(d, n, rgba, w, h) == VP8_STATUS_OK) return failWith(err, kNoMemory);
  return failWith(err, "mesh image cannot be decoded");
}

void* decodeImage(const geo::MeshData& mesh, StagingArena& arena, int& w, int& h, int& levels, std::string& err) {
  const uint8_t* d = mesh.image.data();
  const size_t n = mesh.image.size();
  if (n > 0x7fffffff) return failWith(err, "mesh image cannot be decoded"), nullptr;
  if (mesh.image_mime == "image/webp") {
    if (!WebPGetInfo(d, n, &w, &h) || w <= 0 || h <= 0) return failWith(err, "mesh image cannot be decoded"), nullptr;
    void* rgba = arena.take(mipChainBytes(w, h, &levels));
    if (!rgba) return failWith(err, "staging arena too small for the mesh's texture"), nullptr;
    return decodeWebp(d, n, static_cast<uint8_t*>(rgba), w, h, err) ? rgba : nullptr;
  }
  int channels = 0;
  stbAllocReset();
  stbi_uc* texels = stbi_load_from_memory(d, static_cast<int>(n), &w, &h, &channels, 4);
  if (!texels) return failWith(err, stbAllocFailed() ? kNoMemory : "mesh image cannot be decoded"), nullptr;
  void* rgba = arena.take(mipChainBytes(w, h, &levels));
  if (rgba) std::memcpy(rgba, texels, size_t(w) * size_t(h) * 4);
  stbi_image_free(texels);
  if (!rgba) return failWith(err, "staging arena too small for the mesh's texture"), nullptr;
  return rgba;
}

// Parts: a grid over the box's ground plan (glTF x and z), up to 4 cells
// along its longer side and as many across as keep the cells near square,
// no more cells than the triangles fill at kMinPartTriangles each; an
// impostor (textured) stays whole.
struct PartGrid {
  int nx = 1, nz = 1;
  int cells() const { return nx * nz; }
};

PartGrid partGrid(const geo::MeshData& mesh, const glm::dvec3& half) {
  PartGrid g;
  const size_t most = std::min<size_t>(kMaxMeshParts, mesh.indices.size() / 3 / kMinPartTriangles);
  if (!mesh.image.empty() || most < 2) return g;
  const bool x_long = half.x >= half.z;
  const double along = x_long ? half.x : half.z, across = x_long ? half.z : half.x;
  const int n_along = int(std::min<size_t>(4, most));
  const int n_across = int(std::clamp<double>(std::round(n_along * across / std::max(along, 1e-9)), 1.0,
                                              double(std::min<size_t>(4, most / size_t(n_along)))));
  (x_long ? g.nx : g.nz) = n_along;
  (x_long ? g.nz : g.nx) = n_across;
  return g;
}

// The grid cell of triangle t's centroid (positions relative to the centre).
int partOf(const std::vector<uint32_t>& idx, size_t t, const Vertex* v, const glm::dvec3& half, const PartGrid& g) {
  // Clamped as a double first: a vertex far outside the box (or not finite)
  // must not overflow the int conversion.
  auto cell = [](double c, double h, int n) {
    if (!(h > 0)) return 0;
    const double f = (c + h) / (2 * h) * n;
    return f >= 0 ? int(std::min(f, double(n - 1))) : 0;
  };
  double cx = 0, cz = 0;
  for (int k = 0; k < 3; ++k) {
    cx += v[idx[t + k]].position[0] / 3.0;
    cz += v[idx[t + k]].position[2] / 3.0;
  }
  return cell(cz, half.z, g.nz) * g.nx + cell(cx, half.x, g.nx);
}

// The triangles written part by part (a counting sort by cell, their order
// kept within each), and each non-empty part's range and box into `out`.
// Each triangle's cell is worked out twice, once to count and once to place,
// rather than kept: the staging arena holds nothing beyond the mesh.
void writeParts(const std::vector<uint32_t>& idx, const Vertex* v, const glm::dvec3& half, const PartGrid& g,
                void* indices, bool small, PreparedMesh& out) {
  uint32_t start[kMaxMeshParts + 1] = {};
  for (size_t t = 0; t + 2 < idx.size(); t += 3) start[partOf(idx, t, v, half, g) + 1] += 3;
  for (int c = 0; c < g.cells(); ++c) start[c + 1] += start[c];
  uint32_t at[kMaxMeshParts];
  MeshPart part[kMaxMeshParts];
  for (int c = 0; c < g.cells(); ++c) {
    at[c] = start[c];
    part[c].first = start[c];
    part[c].count = start[c + 1] - start[c];
    for (int k = 0; k < 3; ++k) part[c].lo[k] = FLT_MAX, part[c].hi[k] = -FLT_MAX;
  }
  for (size_t t = 0; t + 2 < idx.size(); t += 3) {
    const int c = partOf(idx, t, v, half, g);
    for (int k = 0; k < 3; ++k) {
      const uint32_t i = idx[t + k];
      if (small)
        static_cast<uint16_t*>(indices)[at[c]++] = static_cast<uint16_t>(i);
      else
        static_cast<uint32_t*>(indices)[at[c]++] = i;
      for (int a = 0; a < 3; ++a) {
        part[c].lo[a] = std::min(part[c].lo[a], v[i].position[a]);
        part[c].hi[a] = std::max(part[c].hi[a], v[i].position[a]);
      }
    }
  }
  out.part_count = 0;
  for (int c = 0; c < g.cells(); ++c)
    if (part[c].count) out.parts[out.part_count++] = part[c];
}

// Area-weighted sums of the triangles' normals at each vertex, accumulated in
// the vertices' position fields (their positions are written after): the
// cross product's length is twice the triangle's area, so raw crosses weight.
void sumFaceNormals(const geo::MeshData& mesh, Vertex* out) {
  for (size_t v = 0; v < mesh.vertexCount(); ++v) std::fill_n(out[v].position, 3, 0.0f);
  const std::vector<float>& p = mesh.positions;
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    const uint32_t ia = mesh.indices[t], ib = mesh.indices[t + 1], ic = mesh.indices[t + 2];
    const glm::vec3 a(p[ia * 3], p[ia * 3 + 1], p[ia * 3 + 2]);
    const glm::vec3 b(p[ib * 3], p[ib * 3 + 1], p[ib * 3 + 2]);
    const glm::vec3 c(p[ic * 3], p[ic * 3 + 1], p[ic * 3 + 2]);
    const glm::vec3 n = glm::cross(b - a, c - a);
    for (uint32_t i : {ia, ib, ic})
      for (int k = 0; k < 3; ++k) out[i].position[k] += n[k];
  }
}

int8_t snorm8(float x) { return static_cast<int8_t>(std::lround(std::clamp(x, -1.0f, 1.0f) * 127.0f)); }

// An untextured mesh's vertices: the unit normal as 3 signed normalised
// bytes (and one of padding), then the sRGB colour (light grey without one).
void writeLit(const geo::MeshData& mesh, bool lines, Vertex* out) {
  const bool own = !mesh.normals.empty();
  if (!own && lines)
    for (size_t v = 0; v < mesh.vertexCount(); ++v) std::fill_n(out[v].position, 3, 0.0f);  // up, below
  else if (!own)
    sumFaceNormals(mesh, out);
  for (size_t v = 0; v < mesh.vertexCount(); ++v) {
    const float* src = own ? &mesh.normals[v * 3] : out[v].position;
    glm::vec3 n(src[0], src[1], src[2]);
    const float len = glm::length(n);
    n = len > 0.0f && std::isfinite(len) ? n / len : glm::vec3(0.0f, 1.0f, 0.0f);
    uint8_t* r = out[v].rest;
    for (int k = 0; k < 3; ++k) r[k] = static_cast<uint8_t>(snorm8(n[k]));
    r[3] = 0;
    if (mesh.colors.empty()) {
      std::memset(r + 4, 200, 3);  // light grey
      r[7] = 255;
    } else {
      std::memcpy(r + 4, &mesh.colors[v * 4], 4);
    }
  }
}

// A textured mesh's vertices: its uv as two floats (its shader reads no
// normal or colour: the texture holds the lit colour).
void writeTextured(const geo::MeshData& mesh, Vertex* out) {
  for (size_t v = 0; v < mesh.vertexCount(); ++v) std::memcpy(out[v].rest, &mesh.texcoords[v * 2], 8);
}

// prepareMesh and prepareLines: triangles, or (lines) pairs of indices.
bool prepare(const geo::MeshData& mesh, bool lines, StagingArena& arena, PreparedMesh& out, std::string& err) {
  out = PreparedMesh{};
  out.lines = lines;
  const size_t nv = mesh.vertexCount();
  if (mesh.positions.size() % 3 != 0 || mesh.indices.size() % (lines ? 2 : 3) != 0)
    return failWith(err, lines ? "line mesh positions are not a multiple of 3 or its indices not pairs"
                               : "mesh positions or indices are not a multiple of 3");
  if (mesh.empty() || nv == 0) return failWith(err, lines ? "line mesh has no segments" : "mesh has no triangles");
  if (nv > 0xFFFFFFFFull || mesh.indices.size() > 0x7FFFFFFFull)
    return failWith(err, "mesh too large for 32-bit indices");
  if (!mesh.normals.empty() && mesh.normals.size() != nv * 3)
    return failWith(err, "mesh normals and positions disagree in count");
  if (!mesh.colors.empty() && mesh.colors.size() != nv * 4)
    return failWith(err, "mesh colors and positions disagree in count");
  if (!mesh.texcoords.empty() && mesh.texcoords.size() != nv * 2)
    return failWith(err, "mesh texcoords and positions disagree in count");
  for (uint32_t i : mesh.indices)
    if (i >= nv) return failWith(err, "mesh index out of range");

  // Box in glTF axes; vertices are stored relative to its centre so floats
  // keep their precision anywhere in the city.
  glm::dvec3 lo(mesh.positions[0], mesh.positions[1], mesh.positions[2]), hi = lo;
  for (size_t v = 1; v < nv; ++v) {
    const glm::dvec3 p(mesh.positions[v * 3], mesh.positions[v * 3 + 1], mesh.positions[v * 3 + 2]);
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  const glm::dvec3 center = (lo + hi) * 0.5, half = (hi - lo) * 0.5;

  auto* vertices = static_cast<Vertex*>(arena.take(nv * sizeof(Vertex)));
  if (!vertices) return failWith(err, "staging arena too small for the mesh's vertices");
  const bool textured = !lines && !mesh.image.empty() && !mesh.texcoords.empty();
  if (textured)
    writeTextured(mesh, vertices);
  else
    writeLit(mesh, lines, vertices);
  for (size_t v = 0; v < nv; ++v)
    for (int k = 0; k < 3; ++k) vertices[v].position[k] = static_cast<float>(mesh.positions[v * 3 + k] - center[k]);

  // 16-bit indices halve index bandwidth for typical blocks. The bound is
  // 65535 exclusive: 0xFFFF is the primitive-restart index a host may enable.
  const bool small = nv < 0xFFFF;
  void* indices = arena.take(mesh.indices.size() * (small ? 2 : 4));
  if (!indices) return failWith(err, "staging arena too small for the mesh's indices");
  const PartGrid grid = lines ? PartGrid{} : partGrid(mesh, half);
  if (grid.cells() > 1) {
    writeParts(mesh.indices, vertices, half, grid, indices, small, out);
  } else if (small) {
    auto* i16 = static_cast<uint16_t*>(indices);
    for (size_t i = 0; i < mesh.indices.size(); ++i) i16[i] = static_cast<uint16_t>(mesh.indices[i]);
  } else {
    std::memcpy(indices, mesh.indices.data(), mesh.indices.size() * 4);
  }

  if (textured) {
    int tw = 0, th = 0, levels = 0;
    void* rgba = decodeImage(mesh, arena, tw, th, levels, err);
    if (!rgba) return false;
    auto* level = static_cast<uint8_t*>(rgba);
    for (int l = 1, w = tw, h = th; l < levels; ++l) {
      const int dw = std::max(1, w / 2), dh = std::max(1, h / 2);
      uint8_t* next = level + size_t(w) * size_t(h) * 4;
      downsample(level, w, h, next, dw, dh);
      level = next, w = dw, h = dh;
    }
    out.rgba = static_cast<const uint8_t*>(rgba);
    out.texture_width = tw;
    out.texture_height = th;
    out.mip_levels = levels;
  }

  out.vertices = reinterpret_cast<const uint8_t*>(vertices);
  out.vertex_count = static_cast<uint32_t>(nv);
  out.indices = indices;
  out.index_count = static_cast<uint32_t>(mesh.indices.size());
  out.index16 = small;
  for (int k = 0; k < 3; ++k) {
    out.center[k] = center[k];
    out.half[k] = half[k];
  }
  return true;
}

}  // namespace

bool outOfMemory(const std::string& err) { return err == kNoMemory; }

bool prepareMesh(const geo::MeshData& mesh, StagingArena& arena, PreparedMesh& out, std::string& err) {
  return prepare(mesh, false, arena, out, err);
}

bool prepareLines(const geo::MeshData& mesh, StagingArena& arena, PreparedMesh& out, std::string& err) {
  return prepare(mesh, true, arena, out, err);
}

}  // namespace blvd::render
