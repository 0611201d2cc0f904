// The bake pipeline: .osm.pbf -> street map -> blocks (ground, half-streets,
// buildings) -> per-block GLB (Draco) -> one package file.
#pragma once
#include <cstdint>
#include <string>

#include "bake/osm_reader.h"

namespace blvd::bake {

struct BakeOptions {
  OsmReadOptions osm;
  bool quiet = false;
  bool draco = true;
};

struct BakeSummary {
  size_t streets = 0, junctions = 0, vertices = 0, cells = 0, blocks = 0, buildings = 0;
  size_t skipped_buildings = 0, bad_polygons = 0, defaulted_heights = 0;
  uint64_t triangles = 0;
  uint64_t source_bytes = 0, package_bytes = 0;
  double seconds = 0;
};

// Throws core::Error on bad input (naming the file) or I/O failure.
BakeSummary bakeCity(const std::string& osm_path, const std::string& out_path, const BakeOptions& opt);

}  // namespace blvd::bake
