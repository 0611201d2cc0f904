// Impostor textures: the captured colour, with its background filled in from
// the nearest covered pixels (so mip-mapping and bilinear filtering at the
// mesh's contour never pull in the clear colour), compressed for the GLB
// (Sillion 97 stores the texture with the mesh; lossy image compression for
// storage as Décoret 99 §5.1 suggests): JPEG, or lossy WebP (libwebp; the
// GLB then names EXT_texture_webp).
#pragma once
#include <cstdint>
#include <vector>

#include "bake/depth_mesh.h"

namespace blvd::bake {

// Fills uncovered pixels (mask 0) by repeated 4-neighbour averaging of
// covered ones (edge padding), in place on a copy of rgba.
std::vector<uint8_t> padTexture(const CaptureImage& img, int iterations = 8);

std::vector<uint8_t> encodeTextureJpeg(const CaptureImage& img, int quality);
// Lossy WebP at `quality` 0..100 (libwebp's scale, near JPEG's); empty when
// libwebp fails.
std::vector<uint8_t> encodeTextureWebp(const CaptureImage& img, int quality);

}  // namespace blvd::bake
