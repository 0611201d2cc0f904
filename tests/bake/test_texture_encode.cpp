// Impostor texture codecs round-trip within a stated error: a 96 × 64 test
// image (smooth sky, facades with window rows, a hard roof edge, uncovered
// pixels that padding fills) through JPEG and lossy WebP at the bake's
// quality 75 decodes to at least 25 dB PSNR against the original over its
// covered pixels (the window rows' hard edges are the hard case for both),
// WebP no more than 1 dB under JPEG, in fewer bytes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include <stb_image.h>
#include <webp/decode.h>

#include "bake/texture_encode.h"

namespace blvd::bake {
namespace {

CaptureImage testImage() {
  CaptureImage img;
  img.width = 96;
  img.height = 64;
  img.rgba.resize(size_t(img.width) * img.height * 4);
  img.mask.resize(size_t(img.width) * img.height);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      uint8_t* p = &img.rgba[(size_t(y) * img.width + x) * 4];
      const bool facade = y > 20 + (x / 24) * 4, window = facade && (x % 8 < 4) && (y % 6 < 3);
      p[0] = facade ? (window ? 60 : 180) : uint8_t(120 + y);
      p[1] = facade ? (window ? 70 : 150) : uint8_t(160 + y / 2);
      p[2] = facade ? (window ? 90 : 120) : 230;
      p[3] = 255;
      img.mask[size_t(y) * img.width + x] = x < 90;  // a strip the capture did not cover
    }
  return img;
}

// PSNR over the covered pixels, RGB.
double psnr(const CaptureImage& ref, const uint8_t* rgba) {
  double se = 0;
  size_t n = 0;
  for (size_t i = 0; i < ref.mask.size(); ++i) {
    if (!ref.mask[i]) continue;
    for (int c = 0; c < 3; ++c) {
      const double d = double(ref.rgba[i * 4 + c]) - double(rgba[i * 4 + c]);
      se += d * d;
      ++n;
    }
  }
  return 10 * std::log10(255.0 * 255.0 / (se / double(n)));
}

TEST(TextureEncode, JpegAndWebpRoundTripWithin25dB) {
  const CaptureImage img = testImage();
  const std::vector<uint8_t> jpeg = encodeTextureJpeg(img, 75), webp = encodeTextureWebp(img, 75);
  ASSERT_FALSE(jpeg.empty());
  ASSERT_FALSE(webp.empty());

  int w = 0, h = 0, c = 0;
  stbi_uc* j = stbi_load_from_memory(jpeg.data(), int(jpeg.size()), &w, &h, &c, 4);
  ASSERT_NE(j, nullptr);
  EXPECT_EQ(w, img.width);
  EXPECT_EQ(h, img.height);
  const double pj = psnr(img, j);
  stbi_image_free(j);

  uint8_t* wp = WebPDecodeRGBA(webp.data(), webp.size(), &w, &h);
  ASSERT_NE(wp, nullptr);
  EXPECT_EQ(w, img.width);
  EXPECT_EQ(h, img.height);
  const double pw = psnr(img, wp);
  WebPFree(wp);

  std::printf("[texture] JPEG q75 %zu bytes, %.1f dB; WebP q75 %zu bytes, %.1f dB\n", jpeg.size(), pj, webp.size(), pw);
  EXPECT_GE(pj, 25.0);
  EXPECT_GE(pw, 25.0);
  EXPECT_GE(pw, pj - 1.0);
  EXPECT_LT(webp.size(), jpeg.size());
}

}  // namespace
}  // namespace blvd::bake
