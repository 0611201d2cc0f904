// GLB (glTF 2.0 binary) encode/decode for the geometry blobs of a package.
//
// Blobs are plain GLB so any glTF viewer opens an extracted one; geometry is
// normally compressed with KHR_draco_mesh_compression (Draco 1.5) or
// EXT_meshopt_compression (meshoptimizer's codecs), see GlbCodec.
//
// Colours: geo::MeshData carries sRGB bytes, glTF's COLOR_0 is linear. The
// encoder converts sRGB -> linear and stores COLOR_0 as normalized unsigned
// byte RGBA; the decoder converts back. 8-bit linear is coarse in the darks:
// a round trip moves sRGB values below 40 by up to 6 levels (near black) and
// the rest by at most 2; alpha is exact. Flat per-face colours show no banding,
// and unorm8 keeps the blobs small; switch COLOR_0 to unorm16 if that changes.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/status.h"
#include "geo/mesh.h"

namespace blvd::package {

// How the geometry of a GLB is stored.
//  - Plain: float/uint buffers, no extension (biggest; any reader).
//  - Draco: KHR_draco_mesh_compression (smallest; slowest to decode).
//  - Meshopt: EXT_meshopt_compression over quantized views
//    (KHR_mesh_quantization): NORMAL octahedral-filtered snorm, POSITION
//    exponential-filtered float, TEXCOORD_0 unorm16. On Monaco's block levels
//    1.30x Draco's package bytes, 0.43x its decode CPU (decision 0009).
enum class GlbCodec { Plain, Draco, Meshopt };

// "plain", "draco", "meshopt"; parseGlbCodec returns false for other names.
const char* glbCodecName(GlbCodec c);
bool parseGlbCodec(const std::string& name, GlbCodec& out);

// Texture coordinates that a decoder computes from the positions instead of
// reading them (BLVD_projected_texcoords, package format 6.0). A depth mesh's
// vertex is an image point of its capture at a depth (Sillion 97 §4.2), so
// its uv is where that capture's camera sees it: u = (row 0 · p) / (row 2 ·
// p), v = (row 1 · p) / (row 2 · p) with p = (x, y, z, 1), clamped to the
// capture's place in the atlas. A layer holds several captures: each vertex
// names its own (`vertex_shot`, stored as a Draco attribute `_SHOT` when
// there is more than one). Decision 0041.
struct TexcoordProjection {
  struct Shot {
    float matrix[12] = {};  // rows u, v, w of a 3x4 projection (row-major)
    float rect[4] = {};     // u0, v0, u1, v1: the capture's place in the atlas
  };
  std::vector<Shot> shots;           // 1 to 256
  std::vector<uint8_t> vertex_shot;  // one per vertex, < shots.size()
};

struct GlbOptions {
  GlbCodec codec = GlbCodec::Draco;
  // With the Draco codec and one level: TEXCOORD_0 is not stored, the decoder
  // projects the positions (TexcoordProjection). The mesh still carries its
  // texcoords; the encoder checks the projection gives them (within
  // kProjectedTexcoordTolerance) before it drops them. Other codecs ignore it.
  const TexcoordProjection* projection = nullptr;
  int position_bits = 16;     // Draco quantization, 1..30; 0 = keep float32 (lossless)
  int normal_bits = 10;       // 1..30; 0 = keep float32 (Meshopt: octahedral bits, at most 16)
  int color_bits = 8;         // only for float colours; our uint8 colours are lossless in Draco
  int texcoord_bits = 14;     // TEXCOORD_0 quantization (impostor uv); 0 = keep float32 (Meshopt: > 0 is unorm16)
  int compression_level = 7;  // 0 (fastest) .. 10 (smallest), as draco_encoder -cl
  // Meshopt: mantissa bits of POSITION's exponential filter (one exponent
  // per vertex), 1..24; 0 = float32 as is. 20 bits keep a position within
  // 2^-19 of its largest coordinate: 4 mm at 2 km from the package origin.
  int meshopt_position_bits = 20;
};

// How far (in uv) a stored texcoord may be from its projection.
inline constexpr float kProjectedTexcoordTolerance = 1.0f / 4096.0f;

// What decodeGlb()/decodeGlbLevel() will return for one encoded mesh, known
// at encode time so a package can record it (runtime pools are sized from
// these counts without decoding). Draco may drop degenerate faces, so these
// come from decoding the encoder's own output, not from the input mesh; a mesh
// without normals decodes unwelded (3 vertices per triangle) and counts so.
struct GlbMeshCounts {
  uint32_t vertices = 0, triangles = 0;
};

// Encodes `mesh` as a GLB with one mesh, one primitive (POSITION, NORMAL if
// the mesh has normals, COLOR_0 if it has colours, TEXCOORD_0 if it has uvs,
// indices), and, when the mesh carries an image, that image in the BIN chunk
// as material 0's base colour texture, unlit (KHR_materials_unlit: impostor
// colour was lit when it was captured). One material
// (white, roughness 1, metallic 0, so vertex colours show), one node and one
// scene. An empty mesh (no triangles) gives a valid GLB with an empty scene,
// which decodeGlb() reads back as an empty mesh.
// Throws core::Error(InvalidArg) when the mesh is inconsistent (array sizes,
// an index >= vertex count, a non-finite position) or an option is out of
// range; core::Error(Internal) when Draco fails to encode.
std::vector<uint8_t> encodeGlb(const geo::MeshData& mesh, const GlbOptions& opt = {}, GlbMeshCounts* counts = nullptr);

// Levels of detail in one GLB (MSFT_lod, node-based): levels[0] is encoded as
// encodeGlb() does (node 0, mesh 0, the only node in the scene, so any viewer
// and decodeGlb() show it), levels[1..] as meshes 1.. on nodes 1.. outside the
// scene, listed in decreasing detail by node 0's
// `extensions.MSFT_lod.ids`. Each level is its own primitive (its own Draco
// buffer or meshopt views), so a level decodes without touching the others.
// MSFT_lod goes in extensionsUsed only: a reader without it still sees level 0.
// Every level must have the same attribute set (normals, colours, uvs); only
// level 0 may carry an image. An empty levels[0] (then the only level) gives
// the empty-scene GLB. `counts` (if given) gets one entry per level.
// Throws as encodeGlb() does, naming the level.
std::vector<uint8_t> encodeGlbLevels(const std::vector<geo::MeshData>& levels, const GlbOptions& opt = {},
                                     std::vector<GlbMeshCounts>* counts = nullptr);

// The most vertices (and a third of the most indices) decodeGlb() produces;
// beyond it returns Unsupported rather than allocate without bound (node
// instancing can multiply a small file into a huge mesh).
inline constexpr size_t kMaxDecodedVertices = size_t{1} << 24;

// Decodes every triangle primitive (TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN;
// points and lines are skipped) of the default scene (or scene 0; with no
// scene at all, of every root node; with no nodes, every mesh once) into one
// mesh, with node transforms applied (matrix or TRS, normals by the inverse
// transpose, winding flipped under mirroring). Draco-compressed primitives are
// decoded and their counts checked against the accessors (Draco streams in
// blvd's profile only, what encodeGlb writes: bitstream 2.2, no attribute of
// Draco type POSITION; others are Unsupported, draco_decode.cpp says why); EXT_meshopt_compression
// bufferViews are decoded (and filtered) before their accessors read them. Missing normals
// become flat normals (the primitive's triangles are unwelded); missing
// colours are white; the material's baseColorFactor multiplies the colours.
// TEXCOORD_0 (or the uv BLVD_projected_texcoords projects, TexcoordProjection)
// is kept when every primitive has it, and then material 0's base
// colour texture (an image in a bufferView) is returned as `out.image` when
// its bytes are PNG or JPEG (`image_mime` says which; other images are dropped).
// Buffers come from the GLB BIN chunk or base64 data: URIs; external files are
// Unsupported, as are sparse accessors, accessors without a bufferView (outside
// Draco) and unknown extensionsRequired.
//
// Never throws and never reads outside [data, data + size): bad input returns
// Corrupt with `err` naming what failed (e.g. "accessors[2]: 24 elements of 12
// bytes at offset 8 run past bufferView 1 (288 bytes)"). `out` is replaced;
// it is empty after a failure.
core::Status decodeGlb(const uint8_t* data, size_t size, geo::MeshData& out, std::string& err);

// As decodeGlb(), but every node of the scene that has an MSFT_lod extension
// is replaced by its level `level` node (ids[level - 1]); level 0 is
// decodeGlb(). NotFound when the scene has no MSFT_lod node, or one has fewer
// than `level` lower levels; Corrupt for a malformed MSFT_lod.
core::Status decodeGlbLevel(const uint8_t* data, size_t size, uint32_t level, geo::MeshData& out, std::string& err);

// A GLB whose JSON is parsed once, for decoding several of its levels one
// after another (the loader decodes a block blob's levels of detail in
// turn): decodeGlbLevel() parses the whole document at every call, about
// 15 % of all decode samples before this (decision 0008 §13). The bytes
// given to open() must stay valid while the document is used. Movable; one
// thread at a time.
class GlbDocument {
 public:
  GlbDocument();
  ~GlbDocument();
  GlbDocument(GlbDocument&&) noexcept;
  GlbDocument& operator=(GlbDocument&&) noexcept;

  // Splits the chunks and parses the JSON: the errors decodeGlb() gives for
  // those. Never throws.
  core::Status open(const uint8_t* data, size_t size, std::string& err);
  bool isOpen() const;
  // decodeGlbLevel() of the bytes given to open(); a document that is not
  // open returns Corrupt saying so.
  core::Status decodeLevel(uint32_t level, geo::MeshData& out, std::string& err) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A copy of a GLB whose whole scene (LOD nodes included) is moved by `offset`
// (glTF axes, metres): its scene roots and MSFT_lod level nodes gain the
// translation, everything else (the Draco buffers, images) is the same bytes.
// For the bake's tiled benchmark packages. Throws core::Error(InvalidArg) when
// the GLB is not one this module wrote (no JSON chunk, a node with a matrix).
std::vector<uint8_t> translateGlb(const uint8_t* data, size_t size, const float offset[3]);

}  // namespace blvd::package
