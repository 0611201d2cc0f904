// The bake pipeline: .osm.pbf -> street map -> blocks (ground, half-streets,
// buildings) -> per-block GLB (Draco) -> one package file.
#pragma once
#include <cstdint>
#include <functional>
#include <string>

#include "bake/block_blob.h"
#include "bake/impostor_bake.h"
#include "bake/lod_chain.h"
#include "bake/osm_reader.h"
#include "bake/shard.h"
#include "bake/terrain_tiles.h"
#include "bake/tile.h"

namespace blvd::bake {

struct BakeOptions {
  OsmReadOptions osm;
  bool quiet = false;
  // How block levels are stored (--block-codec): meshopt blocks decode in
  // 0.43x the CPU time of Draco level 3 for 1.30x the package bytes on
  // Monaco (decision 0009); impostors stay Draco.
  package::GlbCodec block_codec = package::GlbCodec::Meshopt;
  // Draco compression level of the block levels, 0 (fastest decode, biggest)
  // .. 10 (smallest), as draco_encoder -cl (decision 0008 §12: the block
  // decode is most of a prediction's CPU time).
  int draco_level = 3;
  // zstd level every blob is stored at (--blob-compression; 0: as is). The
  // meshopt block levels and the glTF JSON compress well (decision 0029).
  int blob_compression = 19;
  LodOptions lod;
  // A block with a building within this many metres of a street is in its
  // cells' local model too (local_model.h; docs/decisions/0015); 0: only the
  // blocks touching the street and its end junctions.
  double local_radius_m = 20.0;
  // ... and so is a block bordering a street this near a cell's end points
  // (local_model.h); 0: none.
  double junction_radius_m = 8.0;
  TileOptions tile;  // --tile NxM: N x M disconnected copies of the city (benchmarks)
  // --dem: SRTM tiles (bake/dem.h) that cover the city; empty: flat ground.
  // The blocks stand and lie on the terrain, the item buffers and captures
  // look from 1.5 m above it, and the graph's points get heights (ELEV).
  std::vector<std::string> dem;
  // With a DEM, the terrain beyond the blocks: quadtree tiles over the city's
  // box and this margin (bake/terrain_tiles.h), the TERR section.
  TerrainTileOptions terrain_tiles;
  ImpostorOptions impostor;
  // Called with the graph, the impostor results and the LOD totals before the
  // package is written (the CLI writes its HTML bake report from them).
  std::function<void(const graph::StreetGraph&, const ImpostorBakeResult&, const LodStats&)> on_impostors;
  // Chooses the cells that get impostors (all when unset), e.g. a benchmark
  // route; called on the city before tiling (so on copy 0's ids).
  std::function<std::vector<uint32_t>(const graph::StreetGraph&)> select_cells;
  // Bake one shard of the city into a shard file (bake/shard.h), not a
  // package. Not with tile or on_impostors (a shard sees part of the cells).
  ShardSpec shard;
};

struct BakeSummary {
  size_t streets = 0, junctions = 0, vertices = 0, cells = 0, blocks = 0, buildings = 0;
  size_t skipped_buildings = 0, bad_polygons = 0, defaulted_heights = 0;
  uint64_t triangles = 0;  // level 0 (the full model)
  LodStats lod;
  size_t impostors = 0, impostor_cells = 0, item_samples = 0;
  uint64_t impostor_triangles = 0, impostor_bytes = 0;
  double pvs_seconds = 0, impostor_seconds = 0;
  uint64_t source_bytes = 0, package_bytes = 0;
  double street_km = 0;  // street length in the graph, each two-way street once
  // With a DEM: the ground's range under the streets, metres, and its voids filled.
  double ground_min_m = 0, ground_max_m = 0;
  uint64_t dem_voids = 0;
  // With a DEM: TERR's tiles, levels, the root's geometric error and the grid
  // points the DEM does not cover (drawn at sea level).
  uint64_t terrain_tiles = 0, terrain_uncovered = 0;
  uint32_t terrain_levels = 0;
  double terrain_error_m = 0;
  double seconds = 0;
  std::vector<uint32_t> shard_streets;  // a shard's streets (lower half-edges)
};

// Throws core::Error on bad input (naming the file) or I/O failure.
BakeSummary bakeCity(const std::string& osm_path, const std::string& out_path, const BakeOptions& opt);

// What a package holds besides its header and blobs, serialised; every
// package and shard file lays them out with addPackageSections, so a merge
// of shards writes the bytes a single bake writes.
struct PackageSections {
  std::vector<uint8_t> graph, cells, spatial_index, blocks, meta;
};
void addPackageSections(package::PackageWriter& w, PackageSections s, const graph::CellTables& tables);

// The META section of a shard (bake/shard.h) as the merged package has it:
// with the package's blob count, which a shard cannot know.
std::string metaWithBlobCount(const std::vector<uint8_t>& meta, uint32_t blobs);

// Everything in `opt` that changes the package's bytes, and the impostor
// route, as canonical JSON (a shard's options identity).
std::string bakeIdentityJson(const BakeOptions& opt, const std::vector<uint32_t>& route);

}  // namespace blvd::bake
