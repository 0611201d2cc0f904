// A cell's impostor images placed in its slot's atlas (render/slab_atlas.h):
// the memory plan packs every cell to size the atlas, the loader packs the
// cell it decodes and names each image's place in its prepared mesh.
#pragma once
#include <cstdint>
#include <vector>

#include "package/format.h"
#include "render/slab_atlas.h"
#include "stream/city.h"

namespace blvd::runtime {

// The atlas width of a package's cell slots: the header's (3.3), or from its
// widest image and most texels a cell; rounded up to `format`'s grid.
int impostorAtlasWidth(const package::PackageHeader& header,
                       render::AtlasFormat format = render::AtlasFormat::Rgba8);

// The height the bake packed every cell's images into on `format`'s grid
// (the header's: 3.3 for RGBA8, 5.1 for ETC2), or 0 when the header is older.
int packedAtlasHeight(const package::PackageHeader& header, render::AtlasFormat format);

// The atlas height the header gives (packedAtlasHeight) or its maxima bound (for tables that come over the link a page at a
// time, where the plan cannot pack every cell; older headers).
int impostorAtlasHeightBound(const package::PackageHeader& header, int width,
                             render::AtlasFormat format = render::AtlasFormat::Rgba8);

// Scratch for packing one cell's layers, sized once (create time) for the
// package's most layers a cell.
struct ImpostorAtlas {
  std::vector<int> w, h, x, y;
  std::vector<uint32_t> order;
  void resize(size_t layers);
  // Places layers[0..n)'s images: x[i], y[i]. The height they take, or -1
  // when an image is wider than `width` or n is past the size.
  int pack(const stream::LayerInfo* layers, uint32_t n, int width, int align = render::kAtlasAlign);
};

}  // namespace blvd::runtime
