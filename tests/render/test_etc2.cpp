// ETC2 RGB8 (render/etc2.h): blocks decoded by hand from the specification's
// rules, the encoder's round trip within a stated error on a test image, and
// Mesa's decoder (the texture uploaded compressed and read back) agreeing with
// ours pixel for pixel on random blocks of every mode and on encoded ones.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "render/atlas_etc2.h"
#include "render/context.h"
#include "render/etc2.h"
#include "render/gl_api.h"

namespace blvd::render {
namespace {

std::vector<uint8_t> block(uint64_t b) {
  std::vector<uint8_t> out(8);
  for (int i = 7; i >= 0; --i, b >>= 8) out[i] = uint8_t(b);
  return out;
}

void expectPixel(const uint8_t* px, int x, int y, int r, int g, int b) {
  const uint8_t* p = px + (y * 4 + x) * 4;
  EXPECT_EQ(p[0], r) << "pixel " << x << "," << y;
  EXPECT_EQ(p[1], g) << "pixel " << x << "," << y;
  EXPECT_EQ(p[2], b) << "pixel " << x << "," << y;
  EXPECT_EQ(p[3], 255);
}

// Individual mode: bases 4-bit ×17; table 0 is {2, 8}; pixel index 0 adds a,
// 1 adds b, 2 subtracts a, 3 subtracts b; no flip: the left half is x < 2.
TEST(Etc2, DecodesIndividualBlocksAsTheSpecificationSays) {
  uint64_t b = 0;
  b |= uint64_t(8) << 60 | uint64_t(2) << 56;   // R1 = 136, R2 = 34
  b |= uint64_t(4) << 52 | uint64_t(15) << 48;  // G1 = 68, G2 = 255
  b |= uint64_t(2) << 44 | uint64_t(0) << 40;   // B1 = 34, B2 = 0
  b |= uint64_t(0) << 37 | uint64_t(7) << 34;   // tables 0 and 7 ({47, 183})
  // Pixel (0,0): index 1 (lsb); pixel (3,3): index 3 (both bits).
  b |= uint64_t(1) << 0;
  b |= uint64_t(1) << (16 + 15) | uint64_t(1) << 15;
  uint8_t px[64];
  decodeEtc2Block(block(b).data(), px);
  expectPixel(px, 0, 0, 136 + 8, 68 + 8, 34 + 8);
  expectPixel(px, 1, 2, 136 + 2, 68 + 2, 34 + 2);
  expectPixel(px, 2, 0, 34 + 47, 255, 0 + 47);
  expectPixel(px, 3, 3, 0, 255 - 183, 0);
}

// Planar mode: O, H and V equal give one colour everywhere (6-bit and 7-bit
// fields widened by repeating their top bits).
TEST(Etc2, DecodesAFlatPlanarBlock) {
  uint8_t rgba[64];
  for (int i = 0; i < 16; ++i) rgba[i * 4] = 200, rgba[i * 4 + 1] = 100, rgba[i * 4 + 2] = 50, rgba[i * 4 + 3] = 255;
  uint8_t enc[8], px[64];
  encodeEtc2(rgba, 4, 4, 16, enc);
  decodeEtc2Block(enc, px);
  for (int i = 0; i < 16; ++i) {
    EXPECT_LE(std::abs(px[i * 4] - 200), 2);
    EXPECT_LE(std::abs(px[i * 4 + 1] - 100), 1);
    EXPECT_LE(std::abs(px[i * 4 + 2] - 50), 2);
  }
}

// A test image: smooth gradients, hard edges between flat colours (facades
// against sky) and fine noise (foliage), 64 × 48.
std::vector<uint8_t> testImage(int w, int h) {
  std::vector<uint8_t> img(size_t(w) * h * 4);
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> noise(-12, 12);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      uint8_t* p = &img[(size_t(y) * w + x) * 4];
      int c[3];
      if (x < w / 3) c[0] = 40 + 3 * x, c[1] = 90 + 2 * y, c[2] = 200 - x - y;  // gradient
      else if (x < 2 * w / 3) c[0] = c[1] = c[2] = (x / 5 + y / 7) % 2 ? 220 : 60;  // edges
      else c[0] = 70 + noise(rng), c[1] = 120 + noise(rng), c[2] = 50 + noise(rng);  // noise
      for (int k = 0; k < 3; ++k) p[k] = uint8_t(std::clamp(c[k], 0, 255));
      p[3] = 255;
    }
  return img;
}

double psnr(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  double se = 0;
  size_t n = 0;
  for (size_t i = 0; i < a.size(); i += 4)
    for (int k = 0; k < 3; ++k, ++n) se += (double(a[i + k]) - b[i + k]) * (double(a[i + k]) - b[i + k]);
  return 10 * std::log10(255.0 * 255.0 / (se / double(n)));
}

// The round trip's stated error: PSNR at least 32 dB over the test image and
// 30 dB over each third of it (measured: 34.1 dB; 35.1, 35.0 and 32.8 dB for
// the gradient, the edges and the noise).
TEST(Etc2, RoundTripsWithinTheStatedError) {
  const int w = 64, h = 48;
  const std::vector<uint8_t> img = testImage(w, h);
  std::vector<uint8_t> enc(etc2Bytes(w, h)), dec(img.size());
  encodeEtc2(img.data(), w, h, size_t(w) * 4, enc.data());
  decodeEtc2(enc.data(), w, h, dec.data());
  EXPECT_EQ(enc.size(), size_t(w / 4) * (h / 4) * 8);
  EXPECT_GE(psnr(img, dec), 32.0);
  for (int third = 0; third < 3; ++third) {
    std::vector<uint8_t> a, b;
    for (int y = 0; y < h; ++y)
      for (int x = third * w / 3; x < (third + 1) * w / 3; ++x)
        for (int k = 0; k < 4; ++k) {
          a.push_back(img[(size_t(y) * w + x) * 4 + k]);
          b.push_back(dec[(size_t(y) * w + x) * 4 + k]);
        }
    EXPECT_GE(psnr(a, b), 30.0) << "third " << third;
  }
  // Edges past a size that is not a multiple of 4 repeat the last pixels.
  std::vector<uint8_t> odd(etc2Bytes(5, 3));
  encodeEtc2(img.data(), 5, 3, size_t(w) * 4, odd.data());
  EXPECT_EQ(odd.size(), 2u * 8u);
}

// An area larger than the image: the pixels past it repeat its last row and
// column, as a place in an ETC2 atlas needs them (atlas_etc2.h).
TEST(Etc2, AnAreaPastTheImageRepeatsItsEdge) {
  const int w = 64, h = 48;
  const std::vector<uint8_t> img = testImage(w, h);
  const int ow = 72, oh = 56;
  std::vector<uint8_t> enc(etc2Bytes(ow, oh)), dec(size_t(ow) * oh * 4);
  encodeEtc2(img.data(), 5, 3, size_t(w) * 4, enc.data(), ow, oh);
  decodeEtc2(enc.data(), ow, oh, dec.data());
  EXPECT_EQ(enc.size(), size_t(ow / 4) * (oh / 4) * 8);
  // Far past the 5 x 3 corner every block is flat: the corner pixel (4, 2).
  const uint8_t* corner = &img[(size_t(2) * w + 4) * 4];
  for (int y = 8; y < oh; ++y)
    for (int x = 8; x < ow; ++x)
      for (int k = 0; k < 3; ++k)
        ASSERT_LE(std::abs(int(dec[(size_t(y) * ow + x) * 4 + k]) - corner[k]), 4) << x << "," << y;
}

// A prepared image's ETC2 levels: its place (each side rounded up to 32) at
// each of the atlas's four levels, each decoding to that mip level within
// the codec's error, the place's margin repeating the level's edge.
TEST(Etc2, AtlasLevelsCoverThePlaceAtEveryLevel) {
  const int w = 64, h = 48;
  std::vector<uint8_t> texels = testImage(w, h);
  // The mip chain as prepareMesh lays it out (each level 2x2 box-filtered
  // from the one above), from the test image.
  int levels = 0;
  std::vector<uint8_t> chain(mipChainBytes(w, h, &levels));
  std::copy(texels.begin(), texels.end(), chain.begin());
  size_t at = texels.size();
  for (int l = 1, pw = w, ph = h; l < levels; ++l) {
    const int lw = std::max(1, pw / 2), lh = std::max(1, ph / 2);
    const uint8_t* src = &chain[at - size_t(pw) * ph * 4];
    for (int y = 0; y < lh; ++y)
      for (int x = 0; x < lw; ++x)
        for (int k = 0; k < 4; ++k) {
          int sum = 0;
          for (int dy = 0; dy < 2; ++dy)
            for (int dx = 0; dx < 2; ++dx)
              sum += src[(size_t(std::min(2 * y + dy, ph - 1)) * pw + std::min(2 * x + dx, pw - 1)) * 4 + k];
          chain[at + (size_t(y) * lw + x) * 4 + k] = uint8_t((sum + 2) / 4);
        }
    at += size_t(lw) * lh * 4;
    pw = lw, ph = lh;
  }
  PreparedMesh m;
  m.rgba = chain.data();
  m.texture_width = w, m.texture_height = h, m.mip_levels = levels;
  EXPECT_EQ(atlasEtc2Bytes(w, h), uint64_t(64 * 64 + 32 * 32 + 16 * 16 + 8 * 8) / 2);
  EXPECT_EQ(atlasEtc2Bytes(203, 117), uint64_t(224 * 128 + 112 * 64 + 56 * 32 + 28 * 16) / 2);
  std::vector<uint8_t> arena_bytes(atlasEtc2Bytes(w, h) + 16);
  StagingArena arena{arena_bytes.data(), arena_bytes.size(), 0};
  std::string err;
  ASSERT_TRUE(encodeAtlasEtc2(m, arena, err)) << err;
  for (int l = 0; l < 4; ++l) {
    int pw = 0, ph = 0, lw = 0, lh = 0;
    const uint8_t* blocks = atlasEtc2Level(m, l, pw, ph);
    const uint8_t* level = mipLevel(m, l, lw, lh);
    ASSERT_NE(blocks, nullptr);
    EXPECT_EQ(pw, 64 >> l);
    EXPECT_EQ(ph, 64 >> l);
    std::vector<uint8_t> dec(size_t(pw) * ph * 4);
    decodeEtc2(blocks, pw, ph, dec.data());
    double se = 0;
    for (int y = 0; y < ph; ++y)
      for (int x = 0; x < pw; ++x)
        for (int k = 0; k < 3; ++k) {
          const int want = level[(size_t(std::min(y, lh - 1)) * lw + std::min(x, lw - 1)) * 4 + k];
          const double d = double(dec[(size_t(y) * pw + x) * 4 + k]) - want;
          se += d * d;
        }
    // Measured 28.7 dB at level 3 to over 30 at level 0: the box-filtered
    // checkerboard puts three or four greys in a block, which ETC1 holds as
    // two; a level from the wrong image or a shifted one is far below.
    EXPECT_GE(10 * std::log10(255.0 * 255.0 / std::max(1e-9, se / (3.0 * pw * ph))), 27.0) << "level " << l;
  }
  // No room, no levels.
  PreparedMesh again = m;
  again.etc2 = nullptr;
  StagingArena small{arena_bytes.data(), 100, 0};
  EXPECT_FALSE(encodeAtlasEtc2(again, small, err));
  EXPECT_EQ(again.etc2, nullptr);
}

// Mesa decodes what we decode: random blocks (every mode: individual,
// differential, T, H, planar) and the encoder's output, uploaded as
// GL_COMPRESSED_RGB8_ETC2 and read back with glGetTexImage (desktop GL's: on
// OSMesa, Mesa's pure-software desktop context).
TEST(Etc2, MesaDecodesAsWeDo) {
  std::string why;
  auto ctx = createContext(Backend::OSMesa, why);
  ASSERT_NE(ctx, nullptr) << why;
  ASSERT_TRUE(ctx->makeCurrent());
  ASSERT_FALSE(ctx->isGles());
  GlApi gl;
  std::string missing;
  ASSERT_TRUE(gl.load(*ctx, missing)) << missing;
  using CompressedTexImage2D = void (*)(GLenum, GLint, GLenum, GLsizei, GLsizei, GLint, GLsizei, const void*);
  using GetTexImage = void (*)(GLenum, GLint, GLenum, GLenum, void*);
  auto compressed = reinterpret_cast<CompressedTexImage2D>(ctx->getProcAddress("glCompressedTexImage2D"));
  auto get = reinterpret_cast<GetTexImage>(ctx->getProcAddress("glGetTexImage"));
  ASSERT_TRUE(compressed && get);
  const int w = 64, h = 48;
  std::vector<uint8_t> data(etc2Bytes(w, h));
  const std::vector<uint8_t> img = testImage(w, h);
  encodeEtc2(img.data(), w, h, size_t(w) * 4, data.data());
  std::mt19937_64 rng(11);
  for (size_t i = data.size() / 2; i < data.size(); i += 8) {  // the lower half: random blocks
    const std::vector<uint8_t> b = block(rng());
    std::memcpy(&data[i], b.data(), 8);
  }
  GLuint tex = 0;
  gl.GenTextures(1, &tex);
  gl.BindTexture(GL_TEXTURE_2D, tex);
  compressed(GL_TEXTURE_2D, 0, GL_COMPRESSED_RGB8_ETC2, w, h, 0, GLsizei(data.size()), data.data());
  ASSERT_EQ(gl.GetError(), GLenum(GL_NO_ERROR));
  std::vector<uint8_t> mesa(size_t(w) * h * 4), ours(mesa.size());
  gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
  get(GL_TEXTURE_2D, 0, GL_RGBA, GL_UNSIGNED_BYTE, mesa.data());
  ASSERT_EQ(gl.GetError(), GLenum(GL_NO_ERROR));
  gl.DeleteTextures(1, &tex);
  decodeEtc2(data.data(), w, h, ours.data());
  size_t differ = 0;
  for (size_t i = 0; i < ours.size(); ++i) differ += ours[i] != mesa[i];
  EXPECT_EQ(differ, 0u) << "of " << ours.size() << " bytes";
}

}  // namespace
}  // namespace blvd::render
