// A prepared impostor image as an ETC2 atlas takes it (slab_atlas.h,
// AtlasFormat::Etc2): its place's kAtlasLevels levels encoded on the
// preparing thread, so that the render thread only copies whole blocks
// (glCompressedTexSubImage2D) and a slab's atlas holds half a byte a texel
// instead of four (docs/decisions/0039).
#pragma once
#include <cstdint>

#include "render/prepared_mesh.h"

namespace blvd::render {

// Bytes of the ETC2 levels of an image of w × h: its place, each side
// rounded up to kEtc2AtlasAlign, at each of kAtlasLevels levels (level l's
// side is the place's >> l, a whole number of 4×4 blocks).
uint64_t atlasEtc2Bytes(int w, int h);

// Level `level` of a prepared mesh's ETC2 levels: its blocks, rows of
// (w / 4) blocks, and the place's size at that level (w × h texels).
const uint8_t* atlasEtc2Level(const PreparedMesh& mesh, int level, int& w, int& h);

// Encodes `mesh`'s image levels into arena memory and points mesh.etc2 at
// them: atlas level l from the image's mip level l (its last past the chain's
// end), the place's texels past the image repeating its last row and column.
// False with `err` set when the arena is too small or the mesh has no image.
bool encodeAtlasEtc2(PreparedMesh& mesh, StagingArena& arena, std::string& err);

}  // namespace blvd::render
