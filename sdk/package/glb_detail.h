// What the GLB encoder (glb_encode.cpp, tools) and decoder (glb_decode.cpp,
// the runtime) share: the container's and glTF's constants, the sRGB curve,
// and the container split into its chunks.
#pragma once
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "core/status.h"

namespace draco {
class Mesh;
}

namespace blvd::package::glb_detail {

constexpr uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr uint32_t kChunkJson = 0x4E4F534A;  // "JSON"
constexpr uint32_t kChunkBin = 0x004E4942;   // "BIN\0"

constexpr int kUnsignedByte = 5121, kByte = 5120, kUnsignedShort = 5123, kShort = 5122,
              kUnsignedInt = 5125, kFloat = 5126;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;
constexpr int kModeTriangles = 4, kModeStrip = 5, kModeFan = 6;

inline float srgbToLinear(float s) {
  return s <= 0.04045f ? s / 12.92f : std::pow((s + 0.055f) / 1.055f, 2.4f);
}

inline uint8_t unitToByte(float v) {
  if (!(v > 0)) return 0;
  if (v >= 1) return 255;
  return static_cast<uint8_t>(std::lround(v * 255));
}

// BLVD_projected_texcoords (glb.h, TexcoordProjection): the uv at which
// `matrix` (rows u, v, w of a 3x4, row-major) projects position `p`, clamped
// to `rect` (u0, v0, u1, v1). False when the point is not in front of the
// camera (w <= 0) or the result is not finite. In double: the matrix's
// translations are kilometres, its uv a 512th of a unit.
inline bool projectTexcoord(const float matrix[12], const float rect[4], const float p[3], float uv[2]) {
  double r[3];
  for (int k = 0; k < 3; ++k)
    r[k] = double(matrix[4 * k]) * p[0] + double(matrix[4 * k + 1]) * p[1] + double(matrix[4 * k + 2]) * p[2] +
           double(matrix[4 * k + 3]);
  if (!(r[2] > 0.0)) return false;
  for (int k = 0; k < 2; ++k) {
    const double t = r[k] / r[2];
    if (!std::isfinite(t)) return false;
    uv[k] = static_cast<float>(std::fmin(std::fmax(t, double(rect[k])), double(rect[k + 2])));
  }
  return true;
}

inline constexpr const char* kProjectedTexcoords = "BLVD_projected_texcoords";
inline constexpr const char* kShotAttribute = "_SHOT";
inline constexpr size_t kProjectionShotBytes = 64;  // 16 float32: matrix then rect

// The GLB container: header and chunks (JSON first, required; then an
// optional BIN; other chunks are ignored).
struct Chunks {
  const uint8_t* json_data = nullptr;
  size_t json_size = 0;
  const uint8_t* bin = nullptr;
  size_t bin_size = 0;
};

// Corrupt or Unsupported, with `err` naming the chunk and offset, for a bad container.
core::Status splitChunks(const uint8_t* data, size_t size, Chunks& c, std::string& err);

// One Draco-compressed buffer into a mesh (draco_decode.cpp); Corrupt with
// Draco's reason, Unsupported for a stream outside blvd's profile: bitstream
// 2.2, edgebreaker or sequential, no attribute of Draco type POSITION (the
// encoder stores positions as GENERIC; why: draco_decode.cpp). The encoder
// decodes what it wrote back, to check it.
core::Status decodeDracoBuffer(const uint8_t* data, size_t size, std::unique_ptr<draco::Mesh>& mesh, std::string& err);

}  // namespace blvd::package::glb_detail
