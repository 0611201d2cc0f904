// Shelf packing for impostor layer atlases (atlas.h).
#include "bake/atlas.h"

#include <algorithm>
#include <numeric>

namespace blvd::bake {

bool packAtlas(const std::vector<std::pair<int, int>>& sizes, int max_side, int gutter, AtlasLayout& out) {
  out = AtlasLayout{};
  out.at.resize(sizes.size());
  std::vector<size_t> order(sizes.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return sizes[a].second > sizes[b].second; });
  int x = gutter, y = gutter, shelf = 0;  // the current shelf's left edge cursor, top, height
  for (size_t i : order) {
    const auto [w, h] = sizes[i];
    if (w + 2 * gutter > max_side || h + 2 * gutter > max_side) return false;
    if (x + w + gutter > max_side) {  // next shelf
      y += shelf + gutter;
      x = gutter;
      shelf = 0;
    }
    if (y + h + gutter > max_side) return false;
    out.at[i] = {x, y};
    out.width = std::max(out.width, x + w + gutter);
    shelf = std::max(shelf, h);
    x += w + gutter;
  }
  out.height = y + shelf + gutter;
  out.width = (out.width + 3) / 4 * 4;
  out.height = (out.height + 3) / 4 * 4;
  return out.width <= max_side && out.height <= max_side;
}

}  // namespace blvd::bake
