// ETC2 RGB8 after the Khronos Data Format Specification 1.3, §21.1 (the same
// text as the OpenGL ES 3.0.6 specification, annex C.1). Bit n of a block is
// bit n of the 64-bit big-endian value of its 8 bytes.
#include "render/etc2.h"

#include <algorithm>
#include <cstring>

namespace blvd::render {
namespace {

// §21.1, table 68: the intensity modifiers {a, b}; pixel index 0 adds a, 1 adds
// b, 2 subtracts a, 3 subtracts b.
constexpr int kModifiers[8][2] = {{2, 8}, {5, 17}, {9, 29}, {13, 42}, {18, 60}, {24, 80}, {33, 106}, {47, 183}};
// Table 68 by column, and each table's offset (× 3, the sum of a pixel's
// three channel offsets) halfway between a and b: laid out so that one loop
// over the tables vectorizes.
struct ModifierColumns {
  int a[8], b[8], threshold[8];
};
constexpr ModifierColumns modifierColumns() {
  ModifierColumns c{};
  for (int t = 0; t < 8; ++t) {
    c.a[t] = kModifiers[t][0];
    c.b[t] = kModifiers[t][1];
    c.threshold[t] = 3 * (kModifiers[t][0] + kModifiers[t][1]);
  }
  return c;
}
constexpr ModifierColumns kColumns = modifierColumns();
// §21.1, table 71: the T and H modes' distances.
constexpr int kDistances[8] = {3, 6, 11, 16, 23, 32, 41, 64};

int clamp255(int v) { return v < 0 ? 0 : v > 255 ? 255 : v; }
uint32_t bits(uint64_t b, int hi, int lo) { return uint32_t((b >> lo) & ((uint64_t(1) << (hi - lo + 1)) - 1)); }
int extend4(uint32_t v) { return int(v << 4 | v); }
int extend5(uint32_t v) { return int(v << 3 | v >> 2); }
int extend6(uint32_t v) { return int(v << 2 | v >> 4); }
int extend7(uint32_t v) { return int(v << 1 | v >> 6); }
int signed3(uint32_t v) { return v & 4 ? int(v) - 8 : int(v); }
int modifier(int table, uint32_t index) {
  const int m = kModifiers[table][index & 1];
  return index & 2 ? -m : m;
}
// Pixel (x, y)'s two index bits: msb at bit 16 + i, lsb at bit i, i = 4x + y.
uint32_t pixelIndex(uint64_t b, int x, int y) {
  const int i = x * 4 + y;
  return uint32_t((b >> (16 + i) & 1) << 1 | (b >> i & 1));
}

void put(uint8_t* out, int x, int y, const int c[3]) {
  uint8_t* p = out + (y * 4 + x) * 4;
  p[0] = uint8_t(clamp255(c[0]));
  p[1] = uint8_t(clamp255(c[1]));
  p[2] = uint8_t(clamp255(c[2]));
  p[3] = 255;
}

// Individual and differential modes (ETC1): a base colour per half and a
// modifier table per half.
void decodeEtc1(uint64_t b, const int base[2][3], uint8_t* out) {
  const int table[2] = {int(bits(b, 39, 37)), int(bits(b, 36, 34))};
  const bool flip = b >> 32 & 1;
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) {
      const int half = flip ? (y >= 2) : (x >= 2);
      const int m = modifier(table[half], pixelIndex(b, x, y));
      const int c[3] = {base[half][0] + m, base[half][1] + m, base[half][2] + m};
      put(out, x, y, c);
    }
}

void decodePaint(uint64_t b, const int paint[4][3], uint8_t* out) {
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) put(out, x, y, paint[pixelIndex(b, x, y)]);
}

void decodeT(uint64_t b, uint8_t* out) {
  const int c1[3] = {extend4(bits(b, 60, 59) << 2 | bits(b, 57, 56)), extend4(bits(b, 55, 52)), extend4(bits(b, 51, 48))};
  const int c2[3] = {extend4(bits(b, 47, 44)), extend4(bits(b, 43, 40)), extend4(bits(b, 39, 36))};
  const int d = kDistances[bits(b, 35, 34) << 1 | bits(b, 32, 32)];
  const int paint[4][3] = {{c1[0], c1[1], c1[2]},
                           {c2[0] + d, c2[1] + d, c2[2] + d},
                           {c2[0], c2[1], c2[2]},
                           {c2[0] - d, c2[1] - d, c2[2] - d}};
  decodePaint(b, paint, out);
}

void decodeH(uint64_t b, uint8_t* out) {
  const uint32_t r1 = bits(b, 62, 59), g1 = bits(b, 58, 56) << 1 | bits(b, 52, 52),
                 b1 = bits(b, 51, 51) << 3 | bits(b, 49, 47);
  const uint32_t r2 = bits(b, 46, 43), g2 = bits(b, 42, 39), b2 = bits(b, 38, 35);
  const uint32_t order = (r1 << 8 | g1 << 4 | b1) >= (r2 << 8 | g2 << 4 | b2);
  const int d = kDistances[bits(b, 34, 34) << 2 | bits(b, 32, 32) << 1 | order];
  const int c1[3] = {extend4(r1), extend4(g1), extend4(b1)}, c2[3] = {extend4(r2), extend4(g2), extend4(b2)};
  const int paint[4][3] = {{c1[0] + d, c1[1] + d, c1[2] + d},
                           {c1[0] - d, c1[1] - d, c1[2] - d},
                           {c2[0] + d, c2[1] + d, c2[2] + d},
                           {c2[0] - d, c2[1] - d, c2[2] - d}};
  decodePaint(b, paint, out);
}

// §21.1's planar mode: a channel at (x, y) from its corner colours O, H, V
// (extended to 8 bits), before clamping.
int planarChannel(int o, int h, int v, int x, int y) { return (x * (h - o) + y * (v - o) + 4 * o + 2) >> 2; }

void decodePlanar(uint64_t b, uint8_t* out) {
  const int o[3] = {extend6(bits(b, 62, 57)), extend7(bits(b, 56, 56) << 6 | bits(b, 54, 49)),
                    extend6(bits(b, 48, 48) << 5 | bits(b, 44, 43) << 3 | bits(b, 41, 39))};
  const int h[3] = {extend6(bits(b, 38, 34) << 1 | bits(b, 32, 32)), extend7(bits(b, 31, 25)), extend6(bits(b, 24, 19))};
  const int v[3] = {extend6(bits(b, 18, 13)), extend7(bits(b, 12, 6)), extend6(bits(b, 5, 0))};
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) {
      int c[3];
      for (int k = 0; k < 3; ++k) c[k] = planarChannel(o[k], h[k], v[k], x, y);
      put(out, x, y, c);
    }
}

uint64_t load64(const uint8_t* p) {
  uint64_t b = 0;
  for (int i = 0; i < 8; ++i) b = b << 8 | p[i];
  return b;
}

void store64(uint64_t b, uint8_t* p) {
  for (int i = 7; i >= 0; --i, b >>= 8) p[i] = uint8_t(b);
}

// ---- encoder ----

struct Block {
  int px[16][3];  // pixel (x, y) at y * 4 + x
};

// The pixels (y * 4 + x) of each half: [flip][half][i]; no flip splits left
// from right, flip top from bottom.
constexpr uint8_t kHalf[2][2][8] = {{{0, 1, 4, 5, 8, 9, 12, 13}, {2, 3, 6, 7, 10, 11, 14, 15}},
                                    {{0, 1, 2, 3, 4, 5, 6, 7}, {8, 9, 10, 11, 12, 13, 14, 15}}};

// The half's best table and each pixel's index for an 8-bit base colour:
// index bits into `b`, the table into *table; returns the squared error. A
// pixel takes the modifier nearest its mean offset from the base (the one that
// minimises the error before clamping). Tables are compared by that error,
// Σ (m − d_k)² = s − 2·m·d + 3·m² with d = Σ d_k and s = Σ d_k² of the
// pixel's offsets d_k from the base, which clamping can only lower; the
// chosen table's error is then counted exactly, clamped as a decoder does.
int64_t fitHalf(const Block& src, bool flip, int half, const int base[3], uint64_t& b, int* table) {
  const uint8_t* pixels = kHalf[flip][half];
  int d[8], s[8];
  for (int i = 0; i < 8; ++i) {
    const int* p = src.px[pixels[i]];
    const int d0 = p[0] - base[0], d1 = p[1] - base[1], d2 = p[2] - base[2];
    d[i] = d0 + d1 + d2;
    s[i] = d0 * d0 + d1 * d1 + d2 * d2;
  }
  int ad[8];
  for (int i = 0; i < 8; ++i) ad[i] = d[i] < 0 ? -d[i] : d[i];
  // Every table at once (the inner loop vectorizes); 8 pixels of at most
  // 3 × 255² + 3 × 183² each: int holds the sum.
  int table_err[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  for (int i = 0; i < 8; ++i)
    for (int t = 0; t < 8; ++t) {
      const int m = 2 * ad[i] >= kColumns.threshold[t] ? kColumns.b[t] : kColumns.a[t];  // nearest of ±a, ±b to d / 3
      table_err[t] += s[i] + m * (3 * m - 2 * ad[i]);
    }
  int best = INT32_MAX, best_t = 0;
  for (int t = 0; t < 8; ++t)
    if (table_err[t] < best) best = table_err[t], best_t = t;
  int64_t err = 0;
  for (int i = 0; i < 8; ++i) {
    const uint32_t pi = (2 * ad[i] >= kColumns.threshold[best_t] ? 1u : 0u) | (d[i] < 0 ? 2u : 0u);
    const int m = modifier(best_t, pi);
    const int* p = src.px[pixels[i]];
    for (int k = 0; k < 3; ++k) {
      const int e = clamp255(base[k] + m) - p[k];
      err += e * e;
    }
    const int n = (pixels[i] & 3) * 4 + (pixels[i] >> 2);  // the index bit of pixel (x, y) is 4x + y
    b |= uint64_t(pi >> 1) << (16 + n) | uint64_t(pi & 1) << n;
  }
  *table = best_t;
  return err;
}

void halfMean(const Block& src, bool flip, int half, double mean[3]) {
  int sum[3] = {0, 0, 0};
  for (uint8_t i : kHalf[flip][half])
    for (int k = 0; k < 3; ++k) sum[k] += src.px[i][k];
  for (int k = 0; k < 3; ++k) mean[k] = sum[k] / 8.0;
}

int quantize(double v, int levels) { return std::clamp(int(v * (levels - 1) / 255.0 + 0.5), 0, levels - 1); }

// Individual (4-bit bases) or differential (5-bit bases 4 apart at most) with
// flip `flip`, and its squared error; false when the halves' bases are too far
// apart for differential.
bool encodeEtc1(const Block& src, bool flip, bool differential, uint64_t* out, int64_t* err) {
  double mean[2][3];
  halfMean(src, flip, 0, mean[0]);
  halfMean(src, flip, 1, mean[1]);
  const int levels = differential ? 32 : 16;
  int q[2][3], base[2][3];
  for (int h = 0; h < 2; ++h)
    for (int k = 0; k < 3; ++k) {
      q[h][k] = quantize(mean[h][k], levels);
      base[h][k] = differential ? extend5(uint32_t(q[h][k])) : extend4(uint32_t(q[h][k]));
    }
  uint64_t b = 0;
  if (differential) {
    for (int k = 0; k < 3; ++k) {
      const int d = q[1][k] - q[0][k];
      if (d < -4 || d > 3) return false;
      b |= uint64_t(q[0][k]) << (59 - 8 * k) | uint64_t(d & 7) << (56 - 8 * k);
    }
    b |= uint64_t(1) << 33;
  } else {
    for (int k = 0; k < 3; ++k) b |= uint64_t(q[0][k]) << (60 - 8 * k) | uint64_t(q[1][k]) << (56 - 8 * k);
  }
  int t0 = 0, t1 = 0;
  *err = fitHalf(src, flip, 0, base[0], b, &t0) + fitHalf(src, flip, 1, base[1], b, &t1);
  b |= uint64_t(t0) << 37 | uint64_t(t1) << 34 | uint64_t(flip) << 32;
  *out = b;
  return true;
}

// A least-squares plane c = O + x (H - O) / 4 + y (V - O) / 4 per channel,
// quantized to 6/7/6 bits: the corner colours' codes.
struct Plane {
  int o[3], h[3], v[3];
};

Plane fitPlane(const Block& src) {
  Plane q;
  for (int k = 0; k < 3; ++k) {
    int sum = 0, sx = 0, sy = 0;  // Σ p, Σ (2x - 3) p, Σ (2y - 3) p: exact
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 4; ++x) {
        const int p = src.px[y * 4 + x][k];
        sum += p;
        sx += (2 * x - 3) * p;
        sy += (2 * y - 3) * p;
      }
    const double mean = sum / 16.0, bx = sx / 40.0, by = sy / 40.0;  // Σ (x - 1.5)² over the block = 20
    const double a = mean - 1.5 * bx - 1.5 * by;
    const int levels = k == 1 ? 128 : 64;
    q.o[k] = quantize(a, levels);
    q.h[k] = quantize(a + 4 * bx, levels);
    q.v[k] = quantize(a + 4 * by, levels);
  }
  return q;
}

// The plane's squared error as a decoder draws it (decodePlanar), without
// packing and unpacking the block.
int64_t planeError(const Block& src, const Plane& q) {
  int64_t err = 0;
  for (int k = 0; k < 3; ++k) {
    const auto extend = k == 1 ? extend7 : extend6;
    const int o = extend(uint32_t(q.o[k])), h = extend(uint32_t(q.h[k])), v = extend(uint32_t(q.v[k]));
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 4; ++x) {
        const int e = clamp255(planarChannel(o, h, v, x, y)) - src.px[y * 4 + x][k];
        err += e * e;
      }
  }
  return err;
}

// The plane's block, with the free bits set so that it reads as planar (R
// and G in range, B out of range in the differential reading).
uint64_t packPlanar(const Plane& q) {
  const int *o = q.o, *h = q.h, *v = q.v;
  uint64_t b = 0;
  b |= uint64_t(o[0]) << 57;
  b |= uint64_t(o[1] >> 6) << 56 | uint64_t(o[1] & 63) << 49;
  b |= uint64_t(o[2] >> 5) << 48 | uint64_t(o[2] >> 3 & 3) << 43 | uint64_t(o[2] & 7) << 39;
  b |= uint64_t(h[0] >> 1) << 34 | uint64_t(h[0] & 1) << 32;
  b |= uint64_t(h[1]) << 25 | uint64_t(h[2]) << 19;
  b |= uint64_t(v[0]) << 13 | uint64_t(v[1]) << 6 | uint64_t(v[2]);
  b |= uint64_t(1) << 33;  // the differential bit
  // R = bits 63..59 plus dR = bits 58..56 must stay in 0..31: bit 63 picks.
  if (int(bits(b, 62, 59)) + signed3(bits(b, 58, 56)) < 0) b |= uint64_t(1) << 63;
  if (int(bits(b, 54, 51)) + signed3(bits(b, 50, 48)) < 0) b |= uint64_t(1) << 55;
  // B = bits 47..43 plus dB = bits 42..40 must leave 0..31: bits 47..45 and 42.
  if (bits(b, 44, 43) + bits(b, 41, 40) < 4) b |= uint64_t(1) << 42;  // B in 0..3, dB in -4..-1
  else b |= uint64_t(7) << 45;                                         // B in 28..31, dB in 0..3
  return b;
}

uint64_t encodeBlock(const Block& src) {
  uint64_t best = 0;
  int64_t best_err = INT64_MAX;
  // Differential bases have a bit more than individual ones: the individual
  // mode is tried where the halves are too far apart for differential.
  for (int flip = 0; flip < 2; ++flip) {
    uint64_t b = 0;
    int64_t e = 0;
    if (!encodeEtc1(src, flip, true, &b, &e) && !encodeEtc1(src, flip, false, &b, &e)) continue;
    if (e < best_err) best_err = e, best = b;
  }
  if (best_err == 0) return best;
  // The planar block's error as the decoder makes it (its 6/7/6-bit colours
  // hold a flat block closer than ETC1's bases and modifiers often do).
  const Plane plane = fitPlane(src);
  return planeError(src, plane) < best_err ? packPlanar(plane) : best;
}

}  // namespace

size_t etc2Bytes(int w, int h) { return size_t((w + 3) / 4) * size_t((h + 3) / 4) * kEtc2BlockBytes; }

void decodeEtc2Block(const uint8_t* block, uint8_t out[64]) {
  const uint64_t b = load64(block);
  int base[2][3];
  if (!(b >> 33 & 1)) {  // individual
    for (int k = 0; k < 3; ++k) {
      base[0][k] = extend4(bits(b, 63 - 8 * k, 60 - 8 * k));
      base[1][k] = extend4(bits(b, 59 - 8 * k, 56 - 8 * k));
    }
    return decodeEtc1(b, base, out);
  }
  int q[3], q2[3];
  for (int k = 0; k < 3; ++k) {
    q[k] = int(bits(b, 63 - 8 * k, 59 - 8 * k));
    q2[k] = q[k] + signed3(bits(b, 58 - 8 * k, 56 - 8 * k));
  }
  if (q2[0] < 0 || q2[0] > 31) return decodeT(b, out);
  if (q2[1] < 0 || q2[1] > 31) return decodeH(b, out);
  if (q2[2] < 0 || q2[2] > 31) return decodePlanar(b, out);
  for (int k = 0; k < 3; ++k) {
    base[0][k] = extend5(uint32_t(q[k]));
    base[1][k] = extend5(uint32_t(q2[k]));
  }
  decodeEtc1(b, base, out);
}

void decodeEtc2(const uint8_t* data, int w, int h, uint8_t* rgba) {
  uint8_t px[64];
  const int bw = (w + 3) / 4, bh = (h + 3) / 4;
  for (int by = 0; by < bh; ++by)
    for (int bx = 0; bx < bw; ++bx) {
      decodeEtc2Block(data + (size_t(by) * bw + bx) * kEtc2BlockBytes, px);
      for (int y = 0; y < 4 && by * 4 + y < h; ++y)
        for (int x = 0; x < 4 && bx * 4 + x < w; ++x)
          std::memcpy(rgba + (size_t(by * 4 + y) * w + bx * 4 + x) * 4, px + (y * 4 + x) * 4, 4);
    }
}

void encodeEtc2(const uint8_t* rgba, int w, int h, size_t stride, uint8_t* out) {
  encodeEtc2(rgba, w, h, stride, out, w, h);
}

constexpr int kFlatCache = 64;

bool flat(const Block& b) {
  for (int i = 1; i < 16; ++i)
    if (b.px[i][0] != b.px[0][0] || b.px[i][1] != b.px[0][1] || b.px[i][2] != b.px[0][2]) return false;
  return true;
}

void encodeEtc2(const uint8_t* rgba, int w, int h, size_t stride, uint8_t* out, int out_w, int out_h) {
  const int bw = (out_w + 3) / 4, bh = (out_h + 3) / 4;
  Block src;
  // Most of an impostor image is blocks of one colour (a facade, the margin
  // round what a layer shows, a place's padding): the last one's code serves
  // the next of the same colour, as encodeBlock would make it again (the
  // codes of the last 64 colours, by a hash of the colour).
  int flat_colour[kFlatCache];
  uint64_t flat_code[kFlatCache] = {};
  std::fill(flat_colour, flat_colour + kFlatCache, -1);
  for (int by = 0; by < bh; ++by)
    for (int bx = 0; bx < bw; ++bx) {
      for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x) {
          const int sx = std::min(bx * 4 + x, w - 1), sy = std::min(by * 4 + y, h - 1);
          const uint8_t* p = rgba + size_t(sy) * stride + size_t(sx) * 4;
          for (int k = 0; k < 3; ++k) src.px[y * 4 + x][k] = p[k];
        }
      uint64_t code = 0;
      if (!flat(src)) {
        code = encodeBlock(src);
      } else {
        const int colour = src.px[0][0] << 16 | src.px[0][1] << 8 | src.px[0][2];
        const int slot = (colour * 2654435761u) >> 26;  // kFlatCache = 64 slots by colour
        if (colour != flat_colour[slot]) flat_colour[slot] = colour, flat_code[slot] = encodeBlock(src);
        code = flat_code[slot];
      }
      store64(code, out + (size_t(by) * bw + bx) * kEtc2BlockBytes);
    }
}

}  // namespace blvd::render
