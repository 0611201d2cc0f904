#include "render/slab_atlas.h"

#include <algorithm>
#include <cmath>

namespace blvd::render {

int atlasWidth(int max_width, uint64_t max_area, int align) {
  const int side = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(max_area))));
  return atlasRound(std::max({max_width, side, 1}), align);
}

int packSlabAtlas(const int* w, const int* h, uint32_t n, int width, int* x, int* y, uint32_t* order, int align) {
  auto round = [align](int v) { return atlasRound(v, align); };
  for (uint32_t i = 0; i < n; ++i) {
    if (w[i] < 0 || h[i] < 0 || round(w[i]) > width) return -1;
    order[i] = i;
  }
  // Tallest first, ties in the given order: a stable insertion sort (a cell
  // has tens of layers).
  for (uint32_t i = 1; i < n; ++i)
    for (uint32_t j = i; j > 0 && round(h[order[j]]) > round(h[order[j - 1]]); --j)
      std::swap(order[j], order[j - 1]);
  int shelf_y = 0, shelf_h = 0, cursor = 0;
  for (uint32_t k = 0; k < n; ++k) {
    const uint32_t i = order[k];
    const int cw = round(w[i]), ch = round(h[i]);
    x[i] = y[i] = 0;
    if (cw == 0 || ch == 0) continue;  // no texels, no place
    if (cursor + cw > width) shelf_y += shelf_h, shelf_h = 0, cursor = 0;
    if (shelf_h == 0) shelf_h = ch;  // the shelf's first image is its tallest
    x[i] = cursor;
    y[i] = shelf_y;
    cursor += cw;
  }
  return shelf_y + shelf_h;
}

int atlasHeightBound(uint64_t rounded_area, int max_height, int width, int align) {
  if (width <= 0) return 0;
  const uint64_t h =
      2 * rounded_area / static_cast<uint64_t>(width) + static_cast<uint64_t>(atlasRound(max_height, align));
  return atlasRound(static_cast<int>(std::min<uint64_t>(h, 1u << 30)), align);
}

uint64_t atlasBytes(int width, int height, AtlasFormat format) {
  if (width <= 0 || height <= 0) return 0;
  uint64_t bytes = 0;
  for (int l = 0; l < kAtlasLevels; ++l) {
    const uint64_t w = uint64_t(std::max(1, width >> l)), h = uint64_t(std::max(1, height >> l));
    bytes += format == AtlasFormat::Etc2 ? (w + 3) / 4 * ((h + 3) / 4) * 8 : w * h * 4;
  }
  return bytes;
}

}  // namespace blvd::render
