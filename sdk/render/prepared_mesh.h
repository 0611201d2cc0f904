// A mesh converted to the renderer's GPU vertex layout on any thread, without
// GL, into memory the caller owns (the loader thread decodes and
// prepares; the render thread only copies bytes into buffers made at create).
//
// Memory: prepareMesh() writes only into the StagingArena it is given, a bump
// allocator over a fixed block; decoding an embedded JPEG/PNG goes through
// stb, which allocates and frees its own scratch on the calling thread.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>

#include "geo/mesh.h"

namespace blvd::render {

// Interleaved vertex, 20 bytes: position (3 × f32, relative to the mesh's box
// centre), then for an untextured mesh its unit normal (3 × snorm8 and a byte
// of padding) and colour (4 × u8, sRGB), for a textured one its uv (2 × f32)
// in the same 8 bytes: a textured mesh's shader reads no normal or colour.
inline constexpr size_t kVertexBytes = 20;

struct StagingArena {
  uint8_t* base = nullptr;
  size_t capacity = 0;
  size_t used = 0;
  // `bytes` aligned to 16, or nullptr when the arena cannot hold them.
  void* take(size_t bytes);
  void reset() { used = 0; }
};

// A run of a mesh's triangles within a box, for culling finer than the
// mesh: indices [first, first + count), the box relative to the mesh's
// centre (glTF axes).
struct MeshPart {
  uint32_t first = 0, count = 0;
  float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
};
inline constexpr int kMaxMeshParts = 16;
// A part holds this many triangles at least on average (fewer parts else).
inline constexpr uint32_t kMinPartTriangles = 256;

struct PreparedMesh {
  const uint8_t* vertices = nullptr;  // vertex_count × kVertexBytes
  uint32_t vertex_count = 0;
  const void* indices = nullptr;      // uint16 when index16, else uint32
  uint32_t index_count = 0;
  bool index16 = true;
  // texture_width × texture_height × 4, top row first; or null. Its mip chain
  // follows it in memory, mip_levels levels in all (level 0 included), each
  // max(1, w >> l) × max(1, h >> l), 2×2 box-filtered on the preparing
  // thread so that the render thread only copies bytes (mipLevel()).
  const uint8_t* rgba = nullptr;
  int texture_width = 0, texture_height = 0;
  int mip_levels = 0;
  // The image's place as an ETC2 atlas holds it, every level (atlas_etc2.h),
  // or null: encoded on the preparing thread for a slab whose atlas is ETC2.
  const uint8_t* etc2 = nullptr;
  // Where a slab's atlas holds the image (slab_atlas.h: the loader's
  // packSlabAtlas); -1 when not placed (an upload() of its own needs none).
  int atlas_x = -1, atlas_y = -1;
  double center[3] = {0, 0, 0};       // box centre and half extents, glTF axes
  double half[3] = {0, 0, 0};
  // An untextured mesh of 2 × kMinPartTriangles triangles or more has its
  // triangles in parts by where they lie (prepareMesh); 0: one whole.
  MeshPart parts[kMaxMeshParts];
  int part_count = 0;
  bool lines = false;  // indices are pairs, drawn as GL_LINES (prepareLines)

  uint64_t vertexBytes() const { return uint64_t(vertex_count) * kVertexBytes; }
  uint64_t indexBytes() const { return uint64_t(index_count) * (index16 ? 2 : 4); }
  uint64_t textureBytes() const { return uint64_t(texture_width) * uint64_t(texture_height) * 4; }
};

// Bytes of a w × h RGBA8 image and its whole mip chain down to 1 × 1, and the
// number of levels in it.
uint64_t mipChainBytes(int w, int h, int* levels = nullptr);

// Level `level` of a prepared mesh's texture: its texels and size.
const uint8_t* mipLevel(const PreparedMesh& mesh, int level, int& w, int& h);

// Arena bytes prepareMesh() needs at most for a mesh of `vertices` vertices,
// `indices` indices and a texture of w × h (0 × 0 without one).
size_t preparedBytes(uint64_t vertices, uint64_t indices, int texture_width, int texture_height);

// Validates `mesh` (counts agree, indices in range, image decodes), computes
// missing normals (area-weighted) and writes the GPU layout into `arena`,
// the triangles of a large untextured mesh grouped into parts.
// False with `err` set when the mesh is malformed or the arena is too small,
// or when the image decoder could not allocate (outOfMemory(err)).
bool prepareMesh(const geo::MeshData& mesh, StagingArena& arena, PreparedMesh& out, std::string& err);
// The same for line segments: `mesh.indices` are pairs, normals and
// colours as given (up and light grey when absent), no image, no parts.
bool prepareLines(const geo::MeshData& mesh, StagingArena& arena, PreparedMesh& out, std::string& err);
// Whether prepareMesh's `err` is an allocation that failed (the mesh may be good).
bool outOfMemory(const std::string& err);

}  // namespace blvd::render
