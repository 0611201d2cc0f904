#include "runtime/impostor_atlas.h"

#include "render/slab_atlas.h"

namespace blvd::runtime {

int impostorAtlasWidth(const package::PackageHeader& header, render::AtlasFormat format) {
  const int align = render::atlasAlign(format);
  if (header.impostor_atlas_width) return render::atlasRound(header.impostor_atlas_width, align);  // 3.3
  if (header.max_impostor_texture_width == 0) return 0;
  return render::atlasWidth(header.max_impostor_texture_width, header.max_cell_impostor_texture_bytes / 4, align);
}

int packedAtlasHeight(const package::PackageHeader& header, render::AtlasFormat format) {
  return format == render::AtlasFormat::Etc2 ? header.impostor_atlas_etc2_height : header.impostor_atlas_height;
}

// Each image rounded up to the atlas grid adds at most a grid step to each side.
int impostorAtlasHeightBound(const package::PackageHeader& header, int width, render::AtlasFormat format) {
  if (width <= 0) return 0;
  if (const int packed = packedAtlasHeight(header, format)) return packed;
  const uint64_t step = uint64_t(render::atlasAlign(format));
  const uint64_t rounded = header.max_cell_impostor_texture_bytes / 4 +
                           uint64_t(header.max_cell_impostor_layers) *
                               (step * (header.max_impostor_texture_width + header.max_impostor_texture_height) + step * step);
  return render::atlasHeightBound(rounded, header.max_impostor_texture_height, width, int(step));
}

void ImpostorAtlas::resize(size_t layers) {
  w.resize(layers);
  h.resize(layers);
  x.resize(layers);
  y.resize(layers);
  order.resize(layers);
}

int ImpostorAtlas::pack(const stream::LayerInfo* layers, uint32_t n, int width, int align) {
  if (n > w.size()) return -1;
  for (uint32_t i = 0; i < n; ++i) w[i] = layers[i].texture_width, h[i] = layers[i].texture_height;
  return render::packSlabAtlas(w.data(), h.data(), n, width, x.data(), y.data(), order.data(), align);
}

}  // namespace blvd::runtime
