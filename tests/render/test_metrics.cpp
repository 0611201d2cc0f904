// SSIM, bad-pixel share, difference picture (sdk/render/metrics.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "imaging/metrics.h"

namespace blvd::imaging {
namespace {

using Image = std::vector<uint8_t>;

constexpr double kC1 = (0.01 * 255) * (0.01 * 255);
constexpr double kC2 = (0.03 * 255) * (0.03 * 255);

Image constant(int w, int h, uint8_t v) {
  Image img(static_cast<size_t>(w) * h * 4, v);
  for (size_t i = 3; i < img.size(); i += 4) img[i] = 255;
  return img;
}

// Grey texture in [lo, hi]: sines of several frequencies plus a checker,
// so that every 11x11 window has some variance.
Image texture(int w, int h, int lo = 40, int hi = 200) {
  Image img(static_cast<size_t>(w) * h * 4);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double t = 0.5 + 0.2 * std::sin(x * 0.31) * std::cos(y * 0.17) + 0.15 * std::sin((x + 2 * y) * 0.9) +
                       0.1 * (((x / 3 + y / 3) & 1) ? 1 : -1);
      const double v = lo + (hi - lo) * std::clamp(t, 0.0, 1.0);
      uint8_t* p = &img[(static_cast<size_t>(y) * w + x) * 4];
      p[0] = p[1] = p[2] = static_cast<uint8_t>(std::lround(v));
      p[3] = 255;
    }
  }
  return img;
}

// A colour texture, to exercise the luminance weights.
Image colourTexture(int w, int h, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> d(0, 255);
  Image img(static_cast<size_t>(w) * h * 4);
  for (size_t i = 0; i < img.size(); ++i) img[i] = static_cast<uint8_t>(i % 4 == 3 ? 255 : d(rng));
  return img;
}

Image offsetBy(const Image& a, int d) {
  Image b = a;
  for (size_t i = 0; i < b.size(); ++i)
    if (i % 4 != 3) b[i] = static_cast<uint8_t>(std::clamp(int{a[i]} + d, 0, 255));
  return b;
}

// SSIM of two constant images: the contrast-structure term is C2 / C2 = 1.
double constantSsim(double mu_a, double mu_b) {
  return (2 * mu_a * mu_b + kC1) / (mu_a * mu_a + mu_b * mu_b + kC1);
}

double lumaOf(const uint8_t* p) { return 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2]; }

// Independent, direct evaluation of ssim_index.m: the 2-D 11x11 Gaussian
// (121 taps, no separability) over every valid window.
double bruteForceSsim(const Image& a, const Image& b, int w, int h) {
  double g[11][11];
  double sum = 0;
  for (int j = 0; j < 11; ++j)
    for (int i = 0; i < 11; ++i) sum += g[j][i] = std::exp(-((i - 5) * (i - 5) + (j - 5) * (j - 5)) / (2 * 1.5 * 1.5));
  double total = 0;
  for (int y = 0; y + 11 <= h; ++y) {
    for (int x = 0; x + 11 <= w; ++x) {
      double ma = 0, mb = 0, saa = 0, sbb = 0, sab = 0;
      for (int j = 0; j < 11; ++j) {
        for (int i = 0; i < 11; ++i) {
          const size_t o = (static_cast<size_t>(y + j) * w + (x + i)) * 4;
          const double ya = lumaOf(&a[o]), yb = lumaOf(&b[o]), wt = g[j][i] / sum;
          ma += wt * ya;
          mb += wt * yb;
          saa += wt * ya * ya;
          sbb += wt * yb * yb;
          sab += wt * ya * yb;
        }
      }
      const double va = saa - ma * ma, vb = sbb - mb * mb, cov = sab - ma * mb;
      total += ((2 * ma * mb + kC1) * (2 * cov + kC2)) / ((ma * ma + mb * mb + kC1) * (va + vb + kC2));
    }
  }
  return total / ((w - 10.0) * (h - 10.0));
}

TEST(Ssim, IdenticalImagesGiveOne) {
  const auto a = colourTexture(64, 48, 1);
  EXPECT_EQ(ssim(a.data(), a.data(), 64, 48), 1.0);
  const auto t = texture(37, 23);
  const auto copy = t;
  EXPECT_EQ(ssim(t.data(), copy.data(), 37, 23), 1.0);
  EXPECT_TRUE(std::isinf(psnr(t.data(), copy.data(), 37 * 23)));
  EXPECT_EQ(badPixelShare(t.data(), copy.data(), 37, 23), 0.0);
}

TEST(Ssim, ConstantImagesMatchTheClosedForm) {
  const int pairs[][2] = {{100, 110}, {0, 255}, {50, 200}, {0, 0}, {255, 245}, {1, 2}};
  for (const auto& p : pairs) {
    const auto a = constant(40, 30, static_cast<uint8_t>(p[0]));
    const auto b = constant(40, 30, static_cast<uint8_t>(p[1]));
    const double expected = constantSsim(lumaOf(a.data()), lumaOf(b.data()));
    EXPECT_NEAR(ssim(a.data(), b.data(), 40, 30), expected, 1e-12) << p[0] << " vs " << p[1];
    // Below the window size the global fallback gives the same closed form.
    EXPECT_NEAR(ssim(a.data(), b.data(), 7, 5), expected, 1e-12) << p[0] << " vs " << p[1];
  }
  // Spot value: 100 vs 110 grey levels.
  const auto a = constant(20, 20, 100), b = constant(20, 20, 110);
  EXPECT_NEAR(ssim(a.data(), b.data(), 20, 20), (2 * 100.0 * 110 + kC1) / (100.0 * 100 + 110.0 * 110 + kC1), 1e-12);
}

TEST(Ssim, ConstantOffsetOnTextureIsCloseToButBelowOne) {
  const int w = 96, h = 64;
  const auto a = texture(w, h, 40, 200);  // no clipping at +10
  const auto b = offsetBy(a, 10);
  const double s = ssim(a.data(), b.data(), w, h);
  EXPECT_LT(s, 1.0);
  EXPECT_GT(s, 0.98);
  // Variances and covariance are unchanged by an offset, so every local value
  // is the luminance term alone, which is at least its value at the darkest
  // possible mean (40) and at most its value at the brightest (200).
  EXPECT_GE(s, constantSsim(40, 50) - 1e-12);
  EXPECT_LE(s, constantSsim(200, 210) + 1e-12);
  EXPECT_NEAR(s, bruteForceSsim(a, b, w, h), 1e-12);
}

TEST(Ssim, InverseImageIsNegative) {
  const int w = 64, h = 48;
  const auto a = texture(w, h, 0, 255);
  Image b = a;
  for (size_t i = 0; i < b.size(); ++i)
    if (i % 4 != 3) b[i] = static_cast<uint8_t>(255 - a[i]);
  EXPECT_LT(ssim(a.data(), b.data(), w, h), 0.0);
  EXPECT_GE(ssim(a.data(), b.data(), w, h), -1.0);
}

TEST(Ssim, GaussianNoiseLowersSsimMonotonically) {
  const int w = 80, h = 60;
  const auto a = texture(w, h, 60, 190);
  std::mt19937 rng(42);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::vector<double> noise(static_cast<size_t>(w) * h);
  for (double& n : noise) n = unit(rng);
  double prev = 1.0;
  for (double sigma : {1.0, 2.0, 5.0, 10.0, 20.0, 40.0, 80.0}) {
    Image b = a;
    for (size_t i = 0; i < noise.size(); ++i)
      for (int c = 0; c < 3; ++c)
        b[i * 4 + c] = static_cast<uint8_t>(std::clamp(std::lround(a[i * 4 + c] + sigma * noise[i]), 0L, 255L));
    const double s = ssim(a.data(), b.data(), w, h);
    EXPECT_LT(s, prev) << "sigma " << sigma;
    prev = s;
  }
  EXPECT_LT(prev, 0.5);
}

TEST(Ssim, SeparableFilterMatchesDirect2dWindow) {
  const int w = 41, h = 29;
  const auto a = colourTexture(w, h, 7);
  auto b = colourTexture(w, h, 8);
  for (size_t i = 0; i < b.size(); ++i) b[i] = static_cast<uint8_t>((a[i] * 3 + b[i]) / 4);  // correlated
  EXPECT_NEAR(ssim(a.data(), b.data(), w, h), bruteForceSsim(a, b, w, h), 1e-12);
  // Exactly the window size: a single valid window.
  EXPECT_NEAR(ssim(a.data(), b.data(), 11, 11), bruteForceSsim(a, b, 11, 11), 1e-12);
}

TEST(Ssim, SmallImagesUseOneGlobalWindow) {
  // Empty: defined as 1 (nothing differs), like psnr's +infinity.
  EXPECT_EQ(ssim(nullptr, nullptr, 0, 0), 1.0);
  EXPECT_EQ(ssim(nullptr, nullptr, 0, 5), 1.0);
  // 1x1 pixel: the variances are 0, so it is the constant closed form.
  const uint8_t p[4] = {100, 100, 100, 255}, q[4] = {120, 120, 120, 255};
  EXPECT_NEAR(ssim(p, q, 1, 1), constantSsim(100, 120), 1e-12);
  // 10x30 (narrower than 11): uniform global statistics.
  const auto a = colourTexture(10, 30, 3), b = colourTexture(10, 30, 4);
  double ma = 0, mb = 0, saa = 0, sbb = 0, sab = 0;
  for (size_t i = 0; i < 300; ++i) {
    const double ya = lumaOf(&a[i * 4]), yb = lumaOf(&b[i * 4]);
    ma += ya / 300;
    mb += yb / 300;
    saa += ya * ya / 300;
    sbb += yb * yb / 300;
    sab += ya * yb / 300;
  }
  const double expected = ((2 * ma * mb + kC1) * (2 * (sab - ma * mb) + kC2)) /
                          ((ma * ma + mb * mb + kC1) * (saa - ma * ma + sbb - mb * mb + kC2));
  EXPECT_NEAR(ssim(a.data(), b.data(), 10, 30), expected, 1e-9);
  EXPECT_EQ(ssim(a.data(), a.data(), 10, 30), 1.0);
  float untouched = -7.0f;
  EXPECT_NEAR(ssimMap(a.data(), b.data(), 10, 30, &untouched), expected, 1e-9);
  EXPECT_EQ(untouched, -7.0f);
}

TEST(Ssim, MapIsLocalAndAveragesToTheScore) {
  const int w = 60, h = 40;
  const auto a = texture(w, h);
  Image b = a;
  // Change one pixel: only windows covering it (x in 20..30, y in 10..20 of
  // the image, i.e. map columns 15..25, rows 5..15) can differ from 1.
  b[(static_cast<size_t>(15) * w + 25) * 4 + 1] ^= 0x40;
  const int mw = ssimMapExtent(w), mh = ssimMapExtent(h);
  ASSERT_EQ(mw, 50);
  ASSERT_EQ(mh, 30);
  std::vector<float> map(static_cast<size_t>(mw) * mh);
  const double s = ssimMap(a.data(), b.data(), w, h, map.data());
  EXPECT_EQ(s, ssim(a.data(), b.data(), w, h));
  double sum = 0;
  for (int y = 0; y < mh; ++y) {
    for (int x = 0; x < mw; ++x) {
      const float v = map[static_cast<size_t>(y) * mw + x];
      sum += v;
      const bool covers = x >= 15 && x <= 25 && y >= 5 && y <= 15;
      if (!covers) {
        EXPECT_FLOAT_EQ(v, 1.0f) << x << "," << y;
      }
    }
  }
  EXPECT_LT(map[static_cast<size_t>(10) * mw + 20], 1.0f);  // the window centred on the pixel
  EXPECT_NEAR(sum / (mw * mh), s, 1e-6);
  EXPECT_EQ(ssimMapExtent(10), 0);
  EXPECT_EQ(ssimMapExtent(11), 1);
}

TEST(BadPixels, ExactShareOnACraftedImage) {
  const int w = 10, h = 10;
  const auto a = constant(w, h, 100);
  Image b = a;
  auto px = [&](int i) { return &b[static_cast<size_t>(i) * 4]; };
  px(0)[0] = 126;  // +26 on R: 26/255 > 0.10, bad
  px(1)[1] = 74;   // -26 on G: bad
  px(2)[2] = 200;  // +100 on B: bad
  px(3)[0] = 125;  // +25: 25/255 < 0.10, not bad
  px(4)[0] = 125;  // +25 on every channel: still not bad (max, not sum)
  px(4)[1] = 125;
  px(4)[2] = 125;
  px(5)[3] = 0;    // alpha only: ignored
  px(6)[0] = 0;    // -100 and +100 at once: bad
  px(6)[2] = 200;
  EXPECT_DOUBLE_EQ(badPixelShare(a.data(), b.data(), w, h), 4.0 / 100.0);
  EXPECT_DOUBLE_EQ(badPixelShare(b.data(), a.data(), w, h), 4.0 / 100.0);  // symmetric
  // Threshold 0: every differing RGB pixel counts (0..4 and 6).
  EXPECT_DOUBLE_EQ(badPixelShare(a.data(), b.data(), w, h, 0.0), 6.0 / 100.0);
  EXPECT_DOUBLE_EQ(badPixelShare(a.data(), b.data(), w, h, 0.5), 0.0);
  EXPECT_DOUBLE_EQ(pixelError(a.data(), px(6)), 100.0 / 255.0);
  EXPECT_EQ(badPixelShare(nullptr, nullptr, 0, 0), 0.0);
}

TEST(DiffImage, GreyWhereEqualRedWhereBad) {
  const int w = 4, h = 1;
  Image a = constant(w, h, 100);
  Image b = a;
  b[4 * 1 + 0] = 110;  // small difference
  b[4 * 2 + 0] = 160;  // bad (60 levels)
  b[4 * 3 + 1] = 0;    // worse (100 levels, error 0.39)
  Image out(a.size(), 0);
  diffImage(a.data(), b.data(), w, h, out.data());
  const uint8_t grey = 60;  // 0.6 * 100
  EXPECT_EQ(out[0], grey);
  EXPECT_EQ(out[1], grey);
  EXPECT_EQ(out[2], grey);
  for (int i = 0; i < w; ++i) EXPECT_EQ(out[static_cast<size_t>(i) * 4 + 3], 255);
  // Sub-threshold: amber, red > green > blue, but not red-dominated.
  EXPECT_GT(out[4], out[5]);
  EXPECT_GT(out[5], out[6]);
  EXPECT_GT(out[5], grey);
  // Bad: red, the larger error more saturated.
  EXPECT_GT(out[8], 150);
  EXPECT_LT(out[9], grey / 2 + 1);
  EXPECT_GE(out[12], out[8]);
  EXPECT_LE(out[13], out[9]);
  // Pure red from an error of 0.5.
  Image c = constant(1, 1, 0), d = constant(1, 1, 0);
  d[0] = 200;
  uint8_t px[4];
  diffImage(c.data(), d.data(), 1, 1, px);
  EXPECT_EQ(px[0], 255);
  EXPECT_EQ(px[1], 0);
  EXPECT_EQ(px[2], 0);
  // `out` may be one of the inputs.
  Image in_place = b;
  diffImage(a.data(), in_place.data(), w, h, in_place.data());
  EXPECT_EQ(in_place, out);
}

TEST(CompareImages, BundlesTheThreeMetrics) {
  const int w = 32, h = 24;
  const auto a = texture(w, h);
  const auto b = offsetBy(a, 30);
  const ImageMetrics m = compareImages(a.data(), b.data(), w, h);
  EXPECT_EQ(m.psnr, psnr(a.data(), b.data(), static_cast<size_t>(w) * h));
  EXPECT_NEAR(m.psnr, 10 * std::log10(255.0 * 255.0 / 900.0), 1e-9);
  EXPECT_EQ(m.ssim, ssim(a.data(), b.data(), w, h));
  EXPECT_EQ(m.bad_pixels, 1.0);
}

}  // namespace
}  // namespace blvd::imaging
