// Triangle mesh as it travels between bake, package (GLB) and render.
//
// Coordinates follow glTF: x = east, y = up, z = south (= -north), metres in
// the package's local frame. So an extracted GLB stands upright in any viewer.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace blvd::geo {

struct MeshData {
  std::vector<float> positions;  // xyz per vertex
  std::vector<float> normals;    // xyz per vertex, unit length
  std::vector<uint8_t> colors;   // rgba per vertex, sRGB
  std::vector<float> texcoords;  // uv per vertex (textured meshes: impostors), or empty
  std::vector<uint32_t> indices; // triangles, counter-clockwise seen from outside
  // An embedded texture (PNG or JPEG bytes) sampled with texcoords, or empty.
  std::vector<uint8_t> image;
  std::string image_mime;        // "image/png", "image/jpeg" or "image/webp"

  size_t vertexCount() const { return positions.size() / 3; }
  size_t triangleCount() const { return indices.size() / 3; }
  bool empty() const { return indices.empty(); }
  void clear() {
    positions.clear();
    normals.clear();
    colors.clear();
    texcoords.clear();
    indices.clear();
    image.clear();
    image_mime.clear();
  }
  // Appends `o`, offsetting its indices.
  void append(const MeshData& o);
};

// glTF axes from local east/north/up.
inline void enuToGltf(double e, double n, double u, float out[3]) {
  out[0] = static_cast<float>(e);
  out[1] = static_cast<float>(u);
  out[2] = static_cast<float>(-n);
}

}  // namespace blvd::geo
