// One texture for all the captures of an impostor layer: the captures'
// images packed on shelves (rows) into one image, each with a gutter around it
// so that mip-mapping does not blend neighbours. A layer then stays one mesh
// and one texture in the package however many captures it took.
#pragma once
#include <utility>
#include <vector>

namespace blvd::bake {

struct AtlasLayout {
  int width = 0, height = 0;                 // multiples of 4
  std::vector<std::pair<int, int>> at;       // top-left corner of each image, pixels (y down)
};

// Packs images of `sizes` (width, height), tallest first on shelves of at
// most `max_side` pixels, `gutter` pixels apart and from the edges. False
// when they do not fit in max_side x max_side (`out` is then unspecified).
bool packAtlas(const std::vector<std::pair<int, int>>& sizes, int max_side, int gutter, AtlasLayout& out);

}  // namespace blvd::bake
