// ETC2 RGB8 texture blocks (GL_COMPRESSED_RGB8_ETC2, which every OpenGL ES 3.0
// device decodes in hardware): 4×4 pixels in 64 bits, 8× smaller than RGBA8.
// Layout and decoding follow the Khronos Data Format Specification 1.3, §21.1
// ("ETC2 compressed texture image formats", RGB8): individual, differential,
// T, H and planar modes.
//
// The encoder writes the differential mode (both flips, every modifier table,
// each pixel its best modifier; the individual mode where the halves are too
// far apart for it) and the planar mode (least-squares plane), and keeps the
// block with the least squared error (tables compared by their error before
// clamping, two sums a pixel for all eight at once); a block of one colour
// takes the code of the last such block of that colour. It never writes T or
// H blocks, which a decoder must still read. Debian packages no ETC2 encoder
// (docs/decisions/0014 has the alternatives, 0039 the speed).
#pragma once
#include <cstddef>
#include <cstdint>

namespace blvd::render {

constexpr size_t kEtc2BlockBytes = 8;

// Bytes of an ETC2 RGB8 image of w × h pixels (whole 4×4 blocks).
size_t etc2Bytes(int w, int h);

// Encodes RGBA8 pixels (alpha ignored; rows of `stride` bytes) into
// etc2Bytes(w, h) bytes, blocks in rows, each block's 8 bytes big-endian as
// the format stores them. Pixels past the image's edge repeat its last row and
// column.
void encodeEtc2(const uint8_t* rgba, int w, int h, size_t stride, uint8_t* out);
// The same into etc2Bytes(out_w, out_h) bytes for an out_w × out_h area at
// least w × h: pixels past the image repeat its last row and column.
void encodeEtc2(const uint8_t* rgba, int w, int h, size_t stride, uint8_t* out, int out_w, int out_h);

// Decodes one block into 16 RGBA8 pixels (alpha 255), rows of 4.
void decodeEtc2Block(const uint8_t* block, uint8_t out[64]);

// Decodes a whole image into RGBA8 of w × h (rows of w × 4 bytes).
void decodeEtc2(const uint8_t* data, int w, int h, uint8_t* rgba);

}  // namespace blvd::render
