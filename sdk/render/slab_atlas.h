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
// A pure function of the images' sizes: the memory plan runs it over every
// cell to size the atlas, the loader runs it again on the cell it decodes and
// gets the same places. No allocation.
#pragma once
#include <cstdint>

namespace blvd::render {

inline constexpr int kAtlasAlign = 8;
inline constexpr int kAtlasLevels = 4;

inline int atlasRound(int v) { return (v + kAtlasAlign - 1) / kAtlasAlign * kAtlasAlign; }

// An atlas width for images at most `max_width` wide covering at most
// `max_area` texels together: the wider of the widest image and the side of a
// square of that area (a roughly square atlas fits a GL's size limit best).
int atlasWidth(int max_width, uint64_t max_area);

// Places n images (w[i] x h[i], each at most `width` wide) on shelves of an
// atlas `width` wide (a multiple of kAtlasAlign): x[i], y[i] are their
// top-left corners, multiples of kAtlasAlign (an image without texels takes
// no place: 0, 0). `order` is scratch of n entries. Returns the height used (a
// multiple of kAtlasAlign, 0 for none), or -1 when an image is wider than the
// atlas or has a negative size.
int packSlabAtlas(const int* w, const int* h, uint32_t n, int width, int* x, int* y, uint32_t* order);

// The most height packSlabAtlas can need for images of at most `rounded_area`
// texels together after rounding, the tallest `max_height` (rounded): on a
// shelf but the last, the shelf's images and the next shelf's first one are
// wider than the atlas and no shorter than that shelf, so
// height <= 2 area / width + tallest.
int atlasHeightBound(uint64_t rounded_area, int max_height, int width);

// GPU bytes of a width x height RGBA8 atlas with its kAtlasLevels levels.
uint64_t atlasBytes(int width, int height);

}  // namespace blvd::render
