// Still-image codecs for impostor atlases, side by side in one process:
// WebP (libwebp, what the bake writes) and AVIF (libavif: aom to encode,
// dav1d to decode) at a range of settings, over raw RGBA8 images given as
// FILE WIDTH HEIGHT triples (tools/texture_codecs.sh extracts them from a
// package baked near-losslessly). For each setting: the bytes of all images,
// the PSNR of the decoded images against the source (RGB, all pixels), and the
// decode CPU of all images (thread CPU time, the least of three rounds), which
// is what a runtime's loader pays for each cell.
#include <avif/avif.h>
#include <time.h>
#include <webp/decode.h>
#include <webp/encode.h>

#include "raw_images.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {

using Image = RawImage;

double cpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) * 1e3 + double(ts.tv_nsec) * 1e-6;
}

double squaredError(const Image& a, const uint8_t* b) {
  double se = 0;
  for (size_t i = 0; i < a.rgba.size(); i += 4)
    for (int k = 0; k < 3; ++k) se += (double(a.rgba[i + k]) - b[i + k]) * (double(a.rgba[i + k]) - b[i + k]);
  return se;
}

std::vector<uint8_t> encodeWebp(const Image& im, int quality) {
  uint8_t* out = nullptr;
  const size_t n = WebPEncodeRGBA(im.rgba.data(), im.w, im.h, im.w * 4, float(quality), &out);
  std::vector<uint8_t> v(out, out + n);
  WebPFree(out);
  return v;
}

bool decodeWebp(const std::vector<uint8_t>& data, Image& out) {
  return WebPDecodeRGBAInto(data.data(), data.size(), out.rgba.data(), out.rgba.size(), out.w * 4) != nullptr;
}

// quantizer: libavif 0.11's 0 (best) .. 63; speed 0 (slowest) .. 10.
std::vector<uint8_t> encodeAvif(const Image& im, int quantizer, int speed) {
  avifImage* image = avifImageCreate(uint32_t(im.w), uint32_t(im.h), 8, AVIF_PIXEL_FORMAT_YUV420);
  avifRGBImage rgb;
  avifRGBImageSetDefaults(&rgb, image);
  rgb.format = AVIF_RGB_FORMAT_RGBA;
  rgb.pixels = const_cast<uint8_t*>(im.rgba.data());
  rgb.rowBytes = uint32_t(im.w) * 4;
  std::vector<uint8_t> v;
  if (avifImageRGBToYUV(image, &rgb) == AVIF_RESULT_OK) {
    avifEncoder* enc = avifEncoderCreate();
    enc->codecChoice = AVIF_CODEC_CHOICE_AOM;
    enc->minQuantizer = enc->maxQuantizer = quantizer;
    enc->speed = speed;
    enc->maxThreads = 1;
    avifRWData out = AVIF_DATA_EMPTY;
    if (avifEncoderWrite(enc, image, &out) == AVIF_RESULT_OK) v.assign(out.data, out.data + out.size);
    avifRWDataFree(&out);
    avifEncoderDestroy(enc);
  }
  avifImageDestroy(image);
  return v;
}

bool decodeAvif(const std::vector<uint8_t>& data, Image& out) {
  avifDecoder* dec = avifDecoderCreate();
  dec->codecChoice = AVIF_CODEC_CHOICE_DAV1D;
  dec->maxThreads = 1;
  avifImage* image = avifImageCreateEmpty();
  bool ok = avifDecoderReadMemory(dec, image, data.data(), data.size()) == AVIF_RESULT_OK;
  if (ok) {
    avifRGBImage rgb;
    avifRGBImageSetDefaults(&rgb, image);
    rgb.format = AVIF_RGB_FORMAT_RGBA;
    rgb.pixels = out.rgba.data();
    rgb.rowBytes = uint32_t(out.w) * 4;
    ok = int(image->width) == out.w && int(image->height) == out.h && avifImageYUVToRGB(image, &rgb) == AVIF_RESULT_OK;
  }
  avifImageDestroy(image);
  avifDecoderDestroy(dec);
  return ok;
}

template <typename Encode, typename Decode>
void row(const char* codec, const std::string& setting, const std::vector<Image>& images, Encode encode,
         Decode decode) {
  std::vector<std::vector<uint8_t>> coded;
  uint64_t bytes = 0;
  double source_texels = 0;
  for (const Image& im : images) {
    coded.push_back(encode(im));
    bytes += coded.back().size();
    source_texels += double(im.w) * im.h;
  }
  double best = 1e300, se = 0;
  for (int round = 0; round < 3; ++round) {
    double ms = 0;
    se = 0;
    for (size_t i = 0; i < images.size(); ++i) {
      Image out{images[i].w, images[i].h, std::vector<uint8_t>(images[i].rgba.size())};
      const double t0 = cpuMs();
      if (!decode(coded[i], out)) {
        std::fprintf(stderr, "texture_codecs: %s %s: image %zu does not decode\n", codec, setting.c_str(), i);
        std::exit(1);
      }
      ms += cpuMs() - t0;
      se += squaredError(images[i], out.rgba.data());
    }
    best = std::min(best, ms);
  }
  const double psnr = 10 * std::log10(255.0 * 255.0 / (se / (3 * source_texels)));
  std::printf("| %s | %s | %llu | %.3f | %.2f | %.1f |\n", codec, setting.c_str(), (unsigned long long)bytes,
              8.0 * double(bytes) / source_texels, psnr, best);
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<Image> images = readRawImages(argc, argv, "texture_codecs");
  std::printf("| codec | setting | bytes | bits a texel | PSNR dB | decode CPU ms |\n|---|---|---|---|---|---|\n");
  for (int q : {40, 50, 60, 70, 80})
    row("WebP", "quality " + std::to_string(q), images, [q](const Image& im) { return encodeWebp(im, q); },
        decodeWebp);
  for (int quantizer : {20, 26, 32, 38, 44})
    row("AVIF", "quantizer " + std::to_string(quantizer) + ", speed 6", images,
        [quantizer](const Image& im) { return encodeAvif(im, quantizer, 6); }, decodeAvif);
  return 0;
}
