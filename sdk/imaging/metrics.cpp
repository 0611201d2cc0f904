// SSIM (Wang et al. 2004), bad-pixel share and the difference picture. See
// metrics.h for the exact definitions; the comments here say how.
#include "imaging/metrics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace blvd::imaging {
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

// dst[x] = sum over k of g[k] * p[k][x], x < n: one 11-tap pass, horizontal
// (p[k] = row + k) or vertical (p[k] = row k of the window). The kernel is
// symmetric, so taps k and 10 - k share a multiplication. Four outputs at a
// time with GCC/Clang vector extensions (two SSE2 double ops each), plus an
// AVX2 clone picked at load time where the CPU has it (800x480 on the dev VM:
// 7.5 ms with SSE2, 5.7 ms with AVX2). The clone does not enable FMA, so
// both give the same bits.
typedef double Double4 __attribute__((vector_size(32), aligned(8), may_alias));  // unaligned loads

#if defined(__x86_64__) && defined(__ELF__)
#define BLVD_FILTER_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define BLVD_FILTER_CLONES
#endif

BLVD_FILTER_CLONES
void filter11(const double* g, const double* const* p, double* dst, size_t n) {
  // Locals, not g[k] / p[k]: the stores to dst could alias g, which would
  // force a reload of every weight at every step.
  const double g0 = g[0], g1 = g[1], g2 = g[2], g3 = g[3], g4 = g[4], g5 = g[5];
  const double *p0 = p[0], *p1 = p[1], *p2 = p[2], *p3 = p[3], *p4 = p[4], *p5 = p[5];
  const double *p6 = p[6], *p7 = p[7], *p8 = p[8], *p9 = p[9], *p10 = p[10];
  size_t x = 0;
  // A macro, not a function: returning a 32-byte vector from a function
  // compiled without AVX draws -Wpsabi.
#define BLVD_AT(q) (*reinterpret_cast<const Double4*>((q) + x))
  for (; x + 4 <= n; x += 4) {
    const Double4 s = g5 * BLVD_AT(p5) + g0 * (BLVD_AT(p0) + BLVD_AT(p10)) + g1 * (BLVD_AT(p1) + BLVD_AT(p9)) +
                      g2 * (BLVD_AT(p2) + BLVD_AT(p8)) + g3 * (BLVD_AT(p3) + BLVD_AT(p7)) +
                      g4 * (BLVD_AT(p4) + BLVD_AT(p6));
    *reinterpret_cast<Double4*>(dst + x) = s;
  }
#undef BLVD_AT
  for (; x < n; ++x)
    dst[x] = g5 * p5[x] + g0 * (p0[x] + p10[x]) + g1 * (p1[x] + p9[x]) + g2 * (p2[x] + p8[x]) + g3 * (p3[x] + p7[x]) +
             g4 * (p4[x] + p6[x]);
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

  // The five filtered quantities are the local means of a, b, a^2, b^2 and ab
  // (ssim_index.m's mu1, mu2 and the sigma terms before subtracting mu^2).
  // Rows are filtered horizontally into a ring of the last 11 rows, and each
  // output row is filtered vertically from the ring as soon as it is complete,
  // so the working set (about 640 bytes a column) stays in cache. Both passes
  // run over contiguous doubles in filter11(). Accumulating in double keeps
  // E[x^2] - mu^2 exact to ~1e-11 (x^2 <= 65025), far below C2 = 58.5.
  const auto g = gaussianKernel();
  const size_t W = static_cast<size_t>(w), MW = static_cast<size_t>(mw);
  constexpr size_t kQ = 5;  // quantities
  constexpr size_t kWin = static_cast<size_t>(kSsimWindow);
  std::vector<double> in(kQ * W);           // one image row, planar per quantity
  std::vector<double> ring(kWin * kQ * MW);  // [row % 11][quantity][x]
  std::vector<double> acc(kQ * MW);          // one vertically filtered row

  double total = 0;
  for (int y = 0; y < h; ++y) {
    const uint8_t* pa = a + static_cast<size_t>(y) * W * 4;
    const uint8_t* pb = b + static_cast<size_t>(y) * W * 4;
    double* q0 = &in[0];
    double* q1 = &in[W];
    double* q2 = &in[2 * W];
    double* q3 = &in[3 * W];
    double* q4 = &in[4 * W];
    for (size_t x = 0; x < W; ++x) {
      const double va = luma(pa + x * 4), vb = luma(pb + x * 4);
      q0[x] = va;
      q1[x] = vb;
      q2[x] = va * va;
      q3[x] = vb * vb;
      q4[x] = va * vb;
    }
    double* slot = &ring[(static_cast<size_t>(y) % kWin) * kQ * MW];
    for (size_t q = 0; q < kQ; ++q) {
      const double* taps[kSsimWindow];
      for (size_t k = 0; k < kWin; ++k) taps[k] = &in[q * W] + k;
      filter11(g.data(), taps, slot + q * MW, MW);
    }
    if (y < kSsimWindow - 1) continue;

    // Output row oy covers image rows oy .. oy + 10, all in the ring now.
    const size_t oy = static_cast<size_t>(y) - (kWin - 1);
    const double* taps[kSsimWindow];
    for (size_t k = 0; k < kWin; ++k) taps[k] = &ring[((oy + k) % kWin) * kQ * MW];
    filter11(g.data(), taps, acc.data(), kQ * MW);  // the five planes of a ring row are contiguous
    const double* mu_a = &acc[0];
    const double* mu_b = &acc[MW];
    const double* e_aa = &acc[2 * MW];
    const double* e_bb = &acc[3 * MW];
    const double* e_ab = &acc[4 * MW];
    double row_sum = 0;
    for (size_t x = 0; x < MW; ++x) {
      const double ma = mu_a[x], mb = mu_b[x];
      const double v = ssimFormula(ma, mb, e_aa[x] - ma * ma, e_bb[x] - mb * mb, e_ab[x] - ma * mb);
      if (map) map[oy * MW + x] = static_cast<float>(v);
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

}  // namespace blvd::imaging
