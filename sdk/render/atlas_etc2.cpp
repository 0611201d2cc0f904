#include "render/atlas_etc2.h"

#include <algorithm>

#include "render/etc2.h"
#include "render/slab_atlas.h"

namespace blvd::render {
namespace {

int placeSide(int side, int level) { return atlasRound(side, kEtc2AtlasAlign) >> level; }

}  // namespace

uint64_t atlasEtc2Bytes(int w, int h) {
  if (w <= 0 || h <= 0) return 0;
  uint64_t bytes = 0;
  for (int l = 0; l < kAtlasLevels; ++l) bytes += etc2Bytes(placeSide(w, l), placeSide(h, l));
  return bytes;
}

const uint8_t* atlasEtc2Level(const PreparedMesh& mesh, int level, int& w, int& h) {
  if (!mesh.etc2 || level < 0 || level >= kAtlasLevels) return nullptr;
  const uint8_t* p = mesh.etc2;
  for (int l = 0; l < level; ++l) p += etc2Bytes(placeSide(mesh.texture_width, l), placeSide(mesh.texture_height, l));
  w = placeSide(mesh.texture_width, level);
  h = placeSide(mesh.texture_height, level);
  return p;
}

bool encodeAtlasEtc2(PreparedMesh& mesh, StagingArena& arena, std::string& err) {
  if (!mesh.rgba || mesh.mip_levels < 1) return err = "no image to encode as ETC2", false;
  auto* out = static_cast<uint8_t*>(arena.take(atlasEtc2Bytes(mesh.texture_width, mesh.texture_height)));
  if (!out) return err = "staging arena too small for the mesh's ETC2 levels", false;
  mesh.etc2 = out;
  for (int l = 0; l < kAtlasLevels; ++l) {
    int iw = 0, ih = 0;
    const uint8_t* texels = mipLevel(mesh, std::min(l, mesh.mip_levels - 1), iw, ih);
    const int pw = placeSide(mesh.texture_width, l), ph = placeSide(mesh.texture_height, l);
    encodeEtc2(texels, iw, ih, size_t(iw) * 4, out, pw, ph);
    out += etc2Bytes(pw, ph);
  }
  return true;
}

}  // namespace blvd::render
