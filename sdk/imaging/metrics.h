// Image comparison for the route benchmark and the golden-image tests: SSIM,
// the share of bad pixels, and a difference picture. PSNR is `psnr()` in
// image.h (included here, so this header alone gives all four).
//
// Images are RGBA8, tightly packed, top row first, 4 bytes a pixel, as in
// image.h. Alpha is ignored everywhere. `a` is the reference (the full-model
// frame), `b` the image under test. All functions are pure, thread-safe and
// never throw; ssim()/ssimMap() allocate scratch of about 640 bytes per image
// column (0.5 MB at 800 px wide), the others allocate nothing. An 800x480 SSIM
// takes about 6 ms on one core of the dev VM (Xeon, AVX2), badPixelShare 1 ms.
#pragma once
#include <cstddef>
#include <cstdint>

#include "imaging/image.h"

namespace blvd::imaging {

// SSIM, Wang, Bovik, Sheikh & Simoncelli 2004, "Image quality assessment: from
// error visibility to structural similarity", IEEE TIP 13(4), eq. 13 (§III-B)
// with the §III-C settings of the authors' reference ssim_index.m:
//   - luminance Y = 0.299 R + 0.587 G + 0.114 B (Rec.601, what MATLAB's
//     rgb2gray gives), kept in double (not rounded back to 8 bits);
//   - an 11x11 circular-symmetric Gaussian window, sigma = 1.5, normalised
//     to sum 1 (fspecial('gaussian', 11, 1.5)); it is separable, so it is
//     applied as two 1-D passes;
//   - K1 = 0.01, K2 = 0.03, L = 255, so C1 = (K1 L)^2, C2 = (K2 L)^2;
//   - the mean of the SSIM map over the valid windows only, i.e. those fully
//     inside the image ((w-10) x (h-10) of them; filter2(..., 'valid'));
//   - no downsampling (the later ssim.m downsamples by max(1, round(min(w,h)/256));
//     ssim_index.m, which we follow, does not).
// Range [-1, 1]; 1 exactly for identical images.
//
// Images smaller than the window (w < 11 or h < 11): there is no valid
// window, so the one SSIM over the whole image with uniform weights (global
// means, variances and covariance) is returned instead. Empty images
// (w <= 0 or h <= 0) give 1, as psnr() gives +infinity for zero pixels.
double ssim(const uint8_t* a, const uint8_t* b, int w, int h);

// Window size of ssim() and the width (height) of the valid SSIM map along an
// axis of n pixels: n - 10, or 0 when n < 11.
constexpr int kSsimWindow = 11;
constexpr int ssimMapExtent(int n) { return n >= kSsimWindow ? n - (kSsimWindow - 1) : 0; }

// ssim() that also writes the local SSIM of every valid window to `map`
// (ssimMapExtent(w) * ssimMapExtent(h) floats, row-major, top row first; the
// value at map (x, y) belongs to the window centred on pixel (x + 5, y + 5)).
// `map` may be null; nothing is written to it when the map is empty.
// Returns the same value as ssim().
double ssimMap(const uint8_t* a, const uint8_t* b, int w, int h, float* map);

// Threshold of badPixelShare(): 10 % of full scale, the target's "colour more
// than 10 % off".
constexpr double kBadPixelThreshold = 0.10;

// Largest per-channel difference of one pixel, in [0, 1]:
// max over c in {R, G, B} of |a_c - b_c| / 255.
double pixelError(const uint8_t* a_px, const uint8_t* b_px);

// Share in [0, 1] of the w*h pixels whose colour is "more than threshold off":
// pixelError(a, b) > threshold, i.e. some channel differs by more than
// threshold * 255 levels (with 0.10: by 26 levels or more). 0 for empty images.
double badPixelShare(const uint8_t* a, const uint8_t* b, int w, int h,
                     double threshold = kBadPixelThreshold);

// Difference picture for the HTML report, RGBA8 w*h into `out` (caller owns
// it; 4*w*h bytes; may be the same buffer as `a` or `b`):
//   - the reference `a` as dimmed grey, 0.6 * Y(a), where the pixels agree;
//   - sub-threshold differences tinted amber, up to 50 % at the threshold;
//   - bad pixels (pixelError > threshold) red, from 50 % red just above the
//     threshold to pure red at an error of 0.5 and beyond.
// Alpha is 255.
void diffImage(const uint8_t* a, const uint8_t* b, int w, int h, uint8_t* out,
               double threshold = kBadPixelThreshold);

// The three numbers the benchmark reports for a frame against its reference.
struct ImageMetrics {
  double psnr = 0;        // dB, +infinity when equal
  double ssim = 0;        // see ssim()
  double bad_pixels = 0;  // see badPixelShare()
};
ImageMetrics compareImages(const uint8_t* a, const uint8_t* b, int w, int h,
                           double threshold = kBadPixelThreshold);

}  // namespace blvd::imaging
