// The HTML bake report: a map of the street graph with cells coloured by their
// number of impostor layers, impostor thumbnails, and triangles, bytes and bake
// time per impostor.
#pragma once
#include <string>

#include "bake/impostor_bake.h"
#include "graph/street_graph.h"

namespace blvd::cli {

// Writes DIR/index.html, DIR/map.svg and DIR/thumbs/*.jpg. Throws
// core::Error(Io) naming the file that cannot be written.
void writeBakeReport(const std::string& dir, const std::string& source, const graph::StreetGraph& g,
                     const bake::ImpostorBakeResult& r);

}  // namespace blvd::cli
