#include "bake/texture_encode.h"

#include <stb_image_write.h>
#include <webp/encode.h>

namespace blvd::bake {

std::vector<uint8_t> padTexture(const CaptureImage& img, int iterations) {
  const int w = img.width, h = img.height;
  std::vector<uint8_t> rgba = img.rgba;
  std::vector<uint8_t> filled(size_t(w) * h);
  for (size_t i = 0; i < filled.size(); ++i) filled[i] = img.mask.empty() ? rgba[i * 4 + 3] == 255 : img.mask[i] != 0;
  std::vector<uint8_t> next = filled;
  for (int it = 0; it < iterations; ++it) {
    bool changed = false;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = size_t(y) * w + x;
        if (filled[i]) continue;
        int sum[3] = {0, 0, 0}, n = 0;
        const int nb[4][2] = {{-1, 0}, {1, 0}, {0, -1}, {0, 1}};
        for (const auto& d : nb) {
          const int nx = x + d[0], ny = y + d[1];
          if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
          const size_t j = size_t(ny) * w + nx;
          if (!filled[j]) continue;
          for (int c = 0; c < 3; ++c) sum[c] += rgba[j * 4 + c];
          ++n;
        }
        if (!n) continue;
        for (int c = 0; c < 3; ++c) rgba[i * 4 + c] = static_cast<uint8_t>(sum[c] / n);
        next[i] = 1;
        changed = true;
      }
    filled = next;
    if (!changed) break;
  }
  // Whatever the iterations did not reach (an atlas's unused corners) takes
  // the mean colour: flat, so JPEG spends nearly nothing on it.
  uint64_t sum[3] = {0, 0, 0}, n = 0;
  for (size_t i = 0; i < filled.size(); ++i)
    if (filled[i]) {
      for (int c = 0; c < 3; ++c) sum[c] += rgba[i * 4 + c];
      ++n;
    }
  for (size_t i = 0; i < filled.size(); ++i) {
    if (!filled[i] && n)
      for (int c = 0; c < 3; ++c) rgba[i * 4 + c] = static_cast<uint8_t>(sum[c] / n);
    rgba[i * 4 + 3] = 255;
  }
  return rgba;
}

std::vector<uint8_t> encodeTextureJpeg(const CaptureImage& img, int quality) {
  const std::vector<uint8_t> rgba = padTexture(img);
  std::vector<uint8_t> out;
  stbi_write_jpg_to_func(
      [](void* ctx, void* data, int size) {
        auto* v = static_cast<std::vector<uint8_t>*>(ctx);
        v->insert(v->end(), static_cast<uint8_t*>(data), static_cast<uint8_t*>(data) + size);
      },
      &out, img.width, img.height, 4, rgba.data(), quality);
  return out;
}

std::vector<uint8_t> encodeTextureWebp(const CaptureImage& img, int quality) {
  const std::vector<uint8_t> rgba = padTexture(img);
  // RGB: the alpha is all opaque after padding, and WebP stores no alpha plane then.
  std::vector<uint8_t> rgb(size_t(img.width) * size_t(img.height) * 3);
  for (size_t i = 0, n = size_t(img.width) * size_t(img.height); i < n; ++i)
    for (int c = 0; c < 3; ++c) rgb[i * 3 + c] = rgba[i * 4 + c];
  uint8_t* data = nullptr;
  const size_t size = WebPEncodeRGB(rgb.data(), img.width, img.height, img.width * 3, float(quality), &data);
  std::vector<uint8_t> out(data, data + size);
  WebPFree(data);
  return out;
}

}  // namespace blvd::bake
