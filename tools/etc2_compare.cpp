// The ETC2 encoder of an earlier revision (namespace old_etc2, built from
// `git show REV:sdk/render/etc2.cpp` by tools/etc2_compare.sh) against the
// working tree's, side by side in one process: encoding time (the least of
// three rounds each) and PSNR of the round trip, over raw RGBA8 images given
// as FILE WIDTH HEIGHT triples, and the share of 4x4 blocks of one colour.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "old_etc2.h"
#include "raw_images.h"
#include "render/etc2.h"

namespace {

using Image = RawImage;

template <typename Encode, typename Decode>
void run(const std::vector<Image>& images, Encode encode, Decode decode, double& ms, double& se) {
  ms = 1e300;
  se = 0;
  for (int round = 0; round < 3; ++round) {
    double t = 0, e = 0;
    for (const Image& im : images) {
      std::vector<uint8_t> enc(blvd::render::etc2Bytes(im.w, im.h)), dec(im.rgba.size());
      const auto t0 = std::chrono::steady_clock::now();
      encode(im.rgba.data(), im.w, im.h, size_t(im.w) * 4, enc.data());
      t += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      decode(enc.data(), im.w, im.h, dec.data());
      for (size_t i = 0; i < dec.size(); i += 4)
        for (int k = 0; k < 3; ++k) e += (double(im.rgba[i + k]) - dec[i + k]) * (double(im.rgba[i + k]) - dec[i + k]);
    }
    ms = std::min(ms, t);
    se = e;
  }
}

bool flatBlock(const Image& im, int bx, int by) {
  const uint8_t* first = &im.rgba[(size_t(by) * im.w + bx) * 4];
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x)
      for (int k = 0; k < 3; ++k)
        if (im.rgba[(size_t(by + y) * im.w + bx + x) * 4 + k] != first[k]) return false;
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<Image> images = readRawImages(argc, argv, "etc2_compare");
  double texels = 0, blocks = 0, flat = 0;
  for (const Image& im : images) {
    for (int by = 0; by + 4 <= im.h; by += 4)
      for (int bx = 0; bx + 4 <= im.w; bx += 4) ++blocks, flat += flatBlock(im, bx, by);
    texels += double(im.w) * im.h;
  }
  double old_ms, old_se, new_ms, new_se;
  auto old_enc = [](const uint8_t* p, int w, int h, size_t s, uint8_t* o) { old_etc2::encodeEtc2(p, w, h, s, o); };
  auto old_dec = [](const uint8_t* d, int w, int h, uint8_t* o) { old_etc2::decodeEtc2(d, w, h, o); };
  auto new_enc = [](const uint8_t* p, int w, int h, size_t s, uint8_t* o) { blvd::render::encodeEtc2(p, w, h, s, o); };
  auto new_dec = [](const uint8_t* d, int w, int h, uint8_t* o) { blvd::render::decodeEtc2(d, w, h, o); };
  run(images, old_enc, old_dec, old_ms, old_se);
  run(images, new_enc, new_dec, new_ms, new_se);
  auto psnr = [&](double se) { return 10 * std::log10(255.0 * 255.0 / (se / (3 * texels))); };
  std::printf("%zu images, %.2f Mpixel, %.1f %% of 4x4 blocks of one colour\n", images.size(), texels * 1e-6,
              100 * flat / blocks);
  std::printf("earlier: %.1f ms (%.1f Mpixel/s), %.2f dB\n", old_ms, texels * 1e-3 / old_ms, psnr(old_se));
  std::printf("now:     %.1f ms (%.1f Mpixel/s), %.2f dB\n", new_ms, texels * 1e-3 / new_ms, psnr(new_se));
  std::printf("speed-up %.2fx\n", old_ms / new_ms);
  return 0;
}
