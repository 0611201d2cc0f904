// SSIM (Wang et al. 2004), bad-pixel share and the difference picture. See
// metrics.h for the exact definitions; the comments here say how.
#include "render/metrics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace blvd::render {
namespace {

constexpr int kRadius = kSsimWindow / 2;  // 5
constexpr double kSigma = 1.5;
constexpr double kC1 = (0.01 * 255.0) * (0.01 * 255.0);
constexpr double kC2 = (0.03 * 255.0) * (0.03 * 255.0);

// The 2-D window exp(-(x^2 + y^2) / (2 sigma^2)) normalised to sum 1 is the
// outer product of this normalised 1-D kernel with itself, which is what lets
// the filter run as two 1-D passes (22 instead of 121 taps a pixel and map).
std::array<double, kSsimWindow> gaussianKernel() {
  std::array<double, kSsimWindow> g{};
  double sum = 0;
  for (int i = 0; i < kSsimWindow; ++i) {
    const double x = i - kRadius;
    g[static_cast<size_t>(i)] = std::exp(-x * x / (2.0 * kSigma * kSigma));
    sum += g[static_cast<size_t>(i)];
  }
  for (double& v : g) v /= sum;
  return g;
}

inline double luma(const uint8_t* p) { return 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2]; }

// Eq. 13 with local statistics: means, variances and covariance.
inline double ssimFormula(double mu_a, double mu_b, double var_a, double var_b, double cov) {
  return ((2.0 * mu_a * mu_b + kC1) * (2.0 * cov + kC2)) /
         ((mu_a * mu_a + mu_b * mu_b + kC1) * (var_a + var_b + kC2));
}

// Images smaller than the window: one window covering the image, uniform weights.
double globalSsim(const uint8_t* a, const uint8_t* b, size_t n) {
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  for (size_t i = 0; i < n; ++i) {
    const double ya = luma(a + i * 4), yb = luma(b + i * 4);
    sa += ya;
    sb += yb;
    saa += ya * ya;
    sbb += yb * yb;
    sab += ya * yb;
  }
  const double inv = 1.0 / static_cast<double>(n);
  const double ma = sa * inv, mb = sb * inv;
  return ssimFormula(ma, mb, saa * inv - ma * ma, sbb * inv - mb * mb, sab * inv - ma * mb);
}

}  // namespace

double ssimMap(const uint8_t* a, const uint8_t* b, int w, int h, float* map) {
  if (w <= 0 || h <= 0) return 1.0;
  const int mw = ssimMapExtent(w), mh = ssimMapExtent(h);
  if (mw == 0 || mh == 0) return globalSsim(a, b, static_cast<size_t>(w) * static_cast<size_t>(h));

  const auto g = gaussianKernel();
  const size_t W = static_cast<size_t>(w), MW = static_cast<size_t>(mw);

  // Pass 1, horizontal: for every image row, the five filtered quantities
  // (a, b, a^2, b^2, ab) at the mw valid columns, interleaved per column.
  std::vector<double> hz(static_cast<size_t>(h) * MW * 5);
  std::vector<double> ya(W), yb(W);
  for (int y = 0; y < h; ++y) {
    const size_t row = static_cast<size_t>(y) * W;
    for (size_t x = 0; x < W; ++x) {
      ya[x] = luma(a + (row + x) * 4);
      yb[x] = luma(b + (row + x) * 4);
    }
    double* out = &hz[static_cast<size_t>(y) * MW * 5];
    for (size_t x = 0; x < MW; ++x) {
      double s0 = 0, s1 = 0, s2 = 0, s3 = 0, s4 = 0;
      for (size_t k = 0; k < static_cast<size_t>(kSsimWindow); ++k) {
        const double va = ya[x + k], vb = yb[x + k], gk = g[k];
        s0 += gk * va;
        s1 += gk * vb;
        s2 += gk * va * va;
        s3 += gk * vb * vb;
        s4 += gk * va * vb;
      }
      double* o = out + x * 5;
      o[0] = s0;
      o[1] = s1;
      o[2] = s2;
      o[3] = s3;
      o[4] = s4;
    }
  }

  // Pass 2, vertical, one output row at a time, then eq. 13 and the mean.
  std::vector<double> acc(MW * 5);
  double total = 0;
  for (int y = 0; y < mh; ++y) {
    std::fill(acc.begin(), acc.end(), 0.0);
    for (int k = 0; k < kSsimWindow; ++k) {
      const double gk = g[static_cast<size_t>(k)];
      const double* in = &hz[static_cast<size_t>(y + k) * MW * 5];
      for (size_t i = 0; i < MW * 5; ++i) acc[i] += gk * in[i];
    }
    double row_sum = 0;
    for (size_t x = 0; x < MW; ++x) {
      const double* s = &acc[x * 5];
      const double mu_a = s[0], mu_b = s[1];
      const double v = ssimFormula(mu_a, mu_b, s[2] - mu_a * mu_a, s[3] - mu_b * mu_b, s[4] - mu_a * mu_b);
      if (map) map[static_cast<size_t>(y) * MW + x] = static_cast<float>(v);
      row_sum += v;
    }
    total += row_sum;
  }
  return total / (static_cast<double>(mw) * static_cast<double>(mh));
}

double ssim(const uint8_t* a, const uint8_t* b, int w, int h) { return ssimMap(a, b, w, h, nullptr); }

double pixelError(const uint8_t* a_px, const uint8_t* b_px) {
  int m = 0;
  for (int c = 0; c < 3; ++c) m = std::max(m, std::abs(int{a_px[c]} - int{b_px[c]}));
  return m / 255.0;
}

double badPixelShare(const uint8_t* a, const uint8_t* b, int w, int h, double threshold) {
  if (w <= 0 || h <= 0) return 0.0;
  const size_t n = static_cast<size_t>(w) * static_cast<size_t>(h);
  size_t bad = 0;
  for (size_t i = 0; i < n; ++i) bad += pixelError(a + i * 4, b + i * 4) > threshold ? 1 : 0;
  return static_cast<double>(bad) / static_cast<double>(n);
}

void diffImage(const uint8_t* a, const uint8_t* b, int w, int h, uint8_t* out, double threshold) {
  if (w <= 0 || h <= 0) return;
  const size_t n = static_cast<size_t>(w) * static_cast<size_t>(h);
  for (size_t i = 0; i < n; ++i) {
    // Read both pixels before writing: `out` may be `a` or `b`.
    const double e = pixelError(a + i * 4, b + i * 4);
    const double grey = 0.6 * luma(a + i * 4);
    double r = grey, gr = grey, bl = grey;
    if (e > threshold) {
      const double t = 0.5 + 0.5 * std::min(1.0, (e - threshold) / std::max(1e-9, 0.5 - threshold));
      r = grey + t * (255.0 - grey);
      gr = grey * (1.0 - t);
      bl = grey * (1.0 - t);
    } else if (e > 0) {
      const double t = 0.5 * e / std::max(1e-9, threshold);
      r = grey + t * (255.0 - grey);
      gr = grey + t * (191.0 - grey);
      bl = grey * (1.0 - t);
    }
    uint8_t* o = out + i * 4;
    o[0] = static_cast<uint8_t>(std::lround(std::clamp(r, 0.0, 255.0)));
    o[1] = static_cast<uint8_t>(std::lround(std::clamp(gr, 0.0, 255.0)));
    o[2] = static_cast<uint8_t>(std::lround(std::clamp(bl, 0.0, 255.0)));
    o[3] = 255;
  }
}

ImageMetrics compareImages(const uint8_t* a, const uint8_t* b, int w, int h, double threshold) {
  ImageMetrics m;
  const size_t n = w > 0 && h > 0 ? static_cast<size_t>(w) * static_cast<size_t>(h) : 0;
  m.psnr = psnr(a, b, n);
  m.ssim = ssim(a, b, w, h);
  m.bad_pixels = badPixelShare(a, b, w, h, threshold);
  return m;
}

}  // namespace blvd::render
