// The HTML bake report: a map of the street graph with cells coloured by their
// number of impostor layers, impostor thumbnails, triangles, bytes and bake
// time per impostor, and the blocks' levels of detail.
#pragma once
#include <string>

#include "bake/block_blob.h"
#include "bake/impostor_bake.h"
#include "graph/street_graph.h"

namespace blvd::cli {

// Writes DIR/index.html, DIR/map.svg and DIR/thumbs/*.jpg. Throws
// core::Error(Io) naming the file that cannot be written.
void writeBakeReport(const std::string& dir, const std::string& source, const graph::StreetGraph& g,
                     const bake::ImpostorBakeResult& r, const bake::LodStats& lod);

}  // namespace blvd::cli
