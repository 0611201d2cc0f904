// The TERR section: the ground as a quadtree of height-field tiles over the
// package's area and a margin around it, each tile with its geometric error,
// so that a runtime draws the terrain beyond the blocks at the level its
// screen-space error asks for (Yılmaz et al. §3: terrain height fields and the
// city together; the tiles' errors as 3D Tiles' geometricError, chunked LOD
// with skirts as Ulrich's "Rendering massive terrains using chunked level of
// detail control", 2002). docs/package-format.md has the byte layout.
//
// The tree is complete: level L has 2^L × 2^L tiles, stored level by level,
// each level's rows from south to north, a row's tiles from west to east.
// Each tile is `grid` × `grid` heights (a blob: 16-bit steps of one size for
// the whole tree), its corners on the tile's corners, so that tiles of one
// level share their edge vertices exactly.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace blvd::graph {

constexpr uint32_t kTerrainVersion = 1;
constexpr size_t kTerrainHeaderBytes = 96;
constexpr size_t kTerrainRecordBytes = 16;
constexpr uint32_t kTerrainMaxLevels = 12;  // 5.6 million tiles
constexpr uint32_t kTerrainMinGrid = 2, kTerrainMaxGrid = 129;

struct TerrainLayout {
  uint32_t grid = 0;    // heights per tile side
  uint32_t levels = 0;  // 0: the package has no terrain
  double west = 0, south = 0;  // the root tile's south-west corner, local east/north metres
  double size = 0;             // the root tile's side, metres
  float base_m = 0, step_m = 0;  // a height is base_m + step_m × its 16-bit step (metres above the origin height)
  // The most error of any tile of each level (0 past `levels`): what a
  // runtime lowers a level's tiles by, alike, so that they stay joined.
  float level_error_m[kTerrainMaxLevels] = {};
  // A tile's side, which is size / 2^level, and the tree's tile count.
  double tileSize(uint32_t level) const { return size / double(uint64_t(1) << level); }
  uint64_t tiles() const;
};

struct TerrainTile {
  uint32_t level = 0, x = 0, y = 0;  // x east, y north, < 2^level
};

// Tile order (above): the first index of a level, a tile's index and back,
// its children (k = 0..3: west-south, east-south, west-north, east-north) and
// its parent. Callers keep level < kTerrainMaxLevels.
uint64_t terrainFirstOfLevel(uint32_t level);
uint32_t terrainIndex(TerrainTile t);
TerrainTile terrainTileAt(uint32_t index);
uint32_t terrainChild(uint32_t index, uint32_t k);
uint32_t terrainParent(uint32_t index);  // of index > 0

struct TerrainRecord {
  uint32_t blob = 0;    // the heights (encodeTerrainHeights)
  float error_m = 0;    // the most the tile's surface departs from the DEM's, >= each child's
  float min_m = 0, max_m = 0;  // its lowest and highest height (metres above the package's origin height)
};

// Throws core::Error(InvalidArg) for a layout or record a reader would refuse.
std::vector<uint8_t> serializeTerrain(const TerrainLayout& layout, const std::vector<TerrainRecord>& records);
// Throws core::Error(Corrupt) naming the file offset: unknown version, a
// truncated section, a grid or level count out of range, a non-finite or
// empty extent, or a record count that is not the tree's.
TerrainLayout parseTerrainHeader(const uint8_t* data, size_t size, uint64_t file_offset);
// One record (kTerrainRecordBytes at p): empty when good, else why not (blob
// past blob_count, a non-finite or negative error, min > max).
std::string parseTerrainRecord(const uint8_t* p, uint32_t blob_count, TerrainRecord& out);

// A tile's heights as its blob: grid² little-endian u16 steps, rows south to
// north, height = base_m + step × step_m. The rounding (at most half a step)
// is part of the tile's error.
std::vector<uint8_t> encodeTerrainHeights(const float* heights, const TerrainLayout& l);
// Into out[grid²]; false when the blob is not 2 grid² bytes.
bool decodeTerrainHeights(const uint8_t* blob, size_t size, const TerrainLayout& l, float* out);

}  // namespace blvd::graph
