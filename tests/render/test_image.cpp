// PNG round trip and PSNR.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "imaging/image.h"
#include "scene.h"

namespace blvd::imaging {
namespace test = render::test;
namespace {

std::vector<uint8_t> gradient(int w, int h) {
  std::vector<uint8_t> img(static_cast<size_t>(w) * h * 4);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      uint8_t* p = &img[(static_cast<size_t>(y) * w + x) * 4];
      p[0] = static_cast<uint8_t>(x * 255 / (w - 1));
      p[1] = static_cast<uint8_t>(y * 255 / (h - 1));
      p[2] = static_cast<uint8_t>((x + y) & 0xFF);
      p[3] = 255;
    }
  }
  return img;
}

TEST(Psnr, EqualImagesAreInfinite) {
  const auto a = gradient(16, 8);
  EXPECT_TRUE(std::isinf(psnr(a.data(), a.data(), 16 * 8)));
  EXPECT_TRUE(std::isinf(psnr(a.data(), a.data(), 0)));
}

TEST(Psnr, KnownValueAndAlphaIgnored) {
  auto a = gradient(16, 8);
  auto b = a;
  // Every RGB channel off by 5: MSE = 25, PSNR = 10 log10(255^2 / 25).
  for (size_t i = 0; i < b.size(); i += 4) {
    for (int c = 0; c < 3; ++c) b[i + c] = static_cast<uint8_t>(a[i + c] < 128 ? a[i + c] + 5 : a[i + c] - 5);
    b[i + 3] = 0;  // alpha must not count
  }
  EXPECT_NEAR(psnr(a.data(), b.data(), 16 * 8), 10.0 * std::log10(255.0 * 255.0 / 25.0), 1e-9);
  // Symmetric, and a bigger error scores lower.
  EXPECT_DOUBLE_EQ(psnr(a.data(), b.data(), 128), psnr(b.data(), a.data(), 128));
  auto c = a;
  for (size_t i = 0; i < c.size(); i += 4) c[i] = static_cast<uint8_t>(255 - c[i]);
  EXPECT_LT(psnr(a.data(), c.data(), 128), psnr(a.data(), b.data(), 128));
}

TEST(Png, RoundTrip) {
  const auto a = gradient(33, 17);
  std::string err;
  const std::string path = test::outPath("png_round_trip.png");
  ASSERT_TRUE(writePng(path, 33, 17, a.data(), err)) << err;
  int w = 0, h = 0;
  std::vector<uint8_t> b;
  ASSERT_TRUE(readPng(path, w, h, b, err)) << err;
  EXPECT_EQ(w, 33);
  EXPECT_EQ(h, 17);
  EXPECT_EQ(a, b);
}

TEST(Png, ErrorsNameTheFile) {
  std::string err;
  int w = 0, h = 0;
  std::vector<uint8_t> b;
  EXPECT_FALSE(readPng("/nonexistent/x.png", w, h, b, err));
  EXPECT_NE(err.find("/nonexistent/x.png"), std::string::npos) << err;
  const uint8_t px[4] = {1, 2, 3, 4};
  EXPECT_FALSE(writePng("/nonexistent/dir/x.png", 1, 1, px, err));
  EXPECT_NE(err.find("/nonexistent/dir/x.png"), std::string::npos) << err;
}

}  // namespace
}  // namespace blvd::imaging
