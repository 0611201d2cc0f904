// Where a cell's impostor images go in its slab's one texture, the slab
// atlas: shelves filled next-fit in order of decreasing height (NFDH,
// Coffman, Garey, Johnson & Tarjan 1980), each image's place rounded up to
// kAtlasAlign texels so that the atlas's kAtlasLevels mip levels keep the
// images apart (at level 3 an 8-texel step is one texel). Four levels: the
// bake's layer images keep a gutter of 4 texels around what their meshes map
// (impostor_bake.cpp), half a texel at level 3, so bilinear filtering there
// reads nothing of a neighbour; past 8x minification a far impostor is
// sampled from level 3 alone.
//
// An ETC2 atlas (GL_COMPRESSED_RGB8_ETC2, 4 bits a texel: docs/decisions/0039)
// rounds places to kEtc2AtlasAlign texels instead, so that each level's
// places start and end on its 4x4 blocks (at level 3 a 32-texel step is one
// block): a place's blocks hold nothing of a neighbour, and an image uploads
// as whole blocks at every level.
//
// A pure function of the images' sizes: the memory plan runs it over every
// cell to size the atlas, the loader runs it again on the cell it decodes and
// gets the same places. No allocation.
#pragma once
#include <cstdint>

namespace blvd::render {

inline constexpr int kAtlasAlign = 8;
inline constexpr int kEtc2AtlasAlign = 32;
inline constexpr int kAtlasLevels = 4;

// What a slab's atlas holds a texel as.
enum class AtlasFormat : uint8_t {
  Rgba8,  // 4 bytes a texel, places on an 8-texel grid
  Etc2,   // ETC2 RGB8 blocks, half a byte a texel, places on a 32-texel grid
};

inline int atlasAlign(AtlasFormat f) { return f == AtlasFormat::Etc2 ? kEtc2AtlasAlign : kAtlasAlign; }
inline int atlasRound(int v, int align = kAtlasAlign) { return (v + align - 1) / align * align; }

// An atlas width for images at most `max_width` wide covering at most
// `max_area` texels together: the wider of the widest image and the side of a
// square of that area (a roughly square atlas fits a GL's size limit best).
int atlasWidth(int max_width, uint64_t max_area, int align = kAtlasAlign);

// Places n images (w[i] x h[i], each at most `width` wide) on shelves of an
// atlas `width` wide (a multiple of kAtlasAlign): x[i], y[i] are their
// top-left corners, multiples of kAtlasAlign (an image without texels takes
// no place: 0, 0). `order` is scratch of n entries. Returns the height used (a
// multiple of kAtlasAlign, 0 for none), or -1 when an image is wider than the
// atlas or has a negative size.
// `align` (kAtlasAlign or kEtc2AtlasAlign) replaces kAtlasAlign throughout.
int packSlabAtlas(const int* w, const int* h, uint32_t n, int width, int* x, int* y, uint32_t* order,
                  int align = kAtlasAlign);

// The most height packSlabAtlas can need for images of at most `rounded_area`
// texels together after rounding, the tallest `max_height` (rounded): on a
// shelf but the last, the shelf's images and the next shelf's first one are
// wider than the atlas and no shorter than that shelf, so
// height <= 2 area / width + tallest.
int atlasHeightBound(uint64_t rounded_area, int max_height, int width, int align = kAtlasAlign);

// GPU bytes of a width x height atlas with its kAtlasLevels levels (ETC2:
// whole 4x4 blocks of 8 bytes).
uint64_t atlasBytes(int width, int height, AtlasFormat format = AtlasFormat::Rgba8);

}  // namespace blvd::render
