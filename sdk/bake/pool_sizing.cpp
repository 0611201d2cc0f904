#include "bake/pool_sizing.h"

#include <algorithm>
#include <limits>
#include <string>

#include "core/status.h"
#include "render/slab_atlas.h"

namespace blvd::bake {
namespace {

// `v` into a field of type T, or a clear error: a package whose numbers do not
// fit its header cannot be planned for.
template <typename T>
T fit(uint64_t v, const char* field) {
  if (v > std::numeric_limits<T>::max())
    throw core::Error(core::Status::Internal, std::string("package header ") + field + " = " + std::to_string(v) +
                                                  " does not fit in " + std::to_string(sizeof(T) * 8) + " bits");
  return static_cast<T>(v);
}

template <typename T>
void raise(T& field, uint64_t v, const char* name) {
  field = std::max(field, fit<T>(v, name));
}

// The most height any cell's layers (layered then single, the order the
// runtime's loader packs them in) take in an atlas `width` wide on `align`.
int packedHeight(const graph::CellTables& tables, int width, int align) {
  std::vector<int> w, ht, x, y;
  std::vector<uint32_t> order;
  int height = 0;
  for (const graph::CellImpostors& ci : tables.impostors) {
    w.clear(), ht.clear();
    for (const auto* list : {&ci.layered, &ci.single})
      for (const graph::ImpostorLayer& l : *list) w.push_back(l.texture_width), ht.push_back(l.texture_height);
    x.resize(w.size()), y.resize(w.size()), order.resize(w.size());
    const int used = render::packSlabAtlas(w.data(), ht.data(), uint32_t(w.size()), width, x.data(), y.data(),
                                           order.data(), align);
    if (used < 0) throw core::Error(core::Status::Internal, "impostor atlas: a layer is wider than the atlas");
    height = std::max(height, used);
  }
  return height;
}

// The atlas a cell slot holds its impostor images in (render/slab_atlas.h):
// its width from the maxima above, its height what the cells' layers take,
// on the RGBA8 atlas's grid and on the ETC2 one's (5.1).
void fillAtlasSize(const graph::CellTables& tables, package::PackageHeader& h) {
  if (h.max_impostor_texture_width == 0) return;
  const int width = render::atlasWidth(h.max_impostor_texture_width, h.max_cell_impostor_texture_bytes / 4);
  h.impostor_atlas_width = fit<uint16_t>(uint64_t(width), "impostor_atlas_width");
  h.impostor_atlas_height =
      fit<uint16_t>(uint64_t(packedHeight(tables, width, render::kAtlasAlign)), "impostor_atlas_height");
  const int etc2_width = render::atlasRound(width, render::kEtc2AtlasAlign);
  h.impostor_atlas_etc2_height = fit<uint16_t>(
      uint64_t(packedHeight(tables, etc2_width, render::kEtc2AtlasAlign)), "impostor_atlas_etc2_height");
}

}  // namespace

void fillPoolSizing(const graph::StreetGraph& g, const std::vector<graph::BlockRecord>& blocks,
                    const graph::CellTables& tables, const std::function<uint64_t(uint32_t)>& blob_bytes,
                    package::PackageHeader& h) {
  constexpr uint32_t kNoBlob = 0xffffffffu;
  auto bytesOf = [&](uint32_t blob) { return blob == kNoBlob ? uint64_t{0} : blob_bytes(blob); };
  for (const graph::BlockRecord& b : blocks) {
    raise(h.max_block_blob_bytes, bytesOf(b.blob), "max_block_blob_bytes");
    raise(h.max_block_lod0_vertices, b.vertices[0], "max_block_lod0_vertices");
    raise(h.max_block_lod0_triangles, b.triangles[0], "max_block_lod0_triangles");
    raise(h.max_block_vertices, b.allVertices(), "max_block_vertices");
    raise(h.max_block_triangles, b.allTriangles(), "max_block_triangles");
  }
  for (uint32_t c = 0; c < g.cellCount(); ++c) {
    uint64_t n = 0, v0 = 0, t0 = 0, v = 0, t = 0, bytes = 0;
    for (const uint32_t* b = g.local_blocks.begin(c); b != g.local_blocks.end(c); ++b) {
      const graph::BlockRecord& r = blocks.at(*b);
      ++n;
      v0 += r.vertices[0];
      t0 += r.triangles[0];
      v += r.allVertices();
      t += r.allTriangles();
      bytes += bytesOf(r.blob);
    }
    raise(h.max_cell_local_blocks, n, "max_cell_local_blocks");
    raise(h.max_cell_local_lod0_vertices, v0, "max_cell_local_lod0_vertices");
    raise(h.max_cell_local_lod0_triangles, t0, "max_cell_local_lod0_triangles");
    raise(h.max_cell_local_vertices, v, "max_cell_local_vertices");
    raise(h.max_cell_local_triangles, t, "max_cell_local_triangles");
    raise(h.max_cell_local_blob_bytes, bytes, "max_cell_local_blob_bytes");
  }
  for (const graph::CellImpostors& ci : tables.impostors) {
    uint64_t layers = 0, v = 0, t = 0, bytes = 0, tex = 0;
    for (const auto* list : {&ci.layered, &ci.single})
      for (const graph::ImpostorLayer& l : *list) {
        const uint64_t texture = uint64_t{l.texture_width} * l.texture_height * 4;
        ++layers;
        v += l.vertices;
        t += l.triangles;
        bytes += bytesOf(l.blob);
        tex += texture;
        raise(h.max_cell_blob_bytes, bytesOf(l.blob), "max_cell_blob_bytes");
        raise(h.max_impostor_texture_bytes, texture, "max_impostor_texture_bytes");
        raise(h.max_impostor_texture_width, l.texture_width, "max_impostor_texture_width");
        raise(h.max_impostor_texture_height, l.texture_height, "max_impostor_texture_height");
      }
    raise(h.max_cell_impostor_layers, layers, "max_cell_impostor_layers");
    raise(h.max_cell_impostor_vertices, v, "max_cell_impostor_vertices");
    raise(h.max_cell_impostor_triangles, t, "max_cell_impostor_triangles");
    raise(h.max_cell_impostor_blob_bytes, bytes, "max_cell_impostor_blob_bytes");
    raise(h.max_cell_impostor_texture_bytes, tex, "max_cell_impostor_texture_bytes");
  }
  fillAtlasSize(tables, h);
}

}  // namespace blvd::bake
