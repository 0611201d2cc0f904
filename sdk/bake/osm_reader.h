// Reads an OpenStreetMap extract (libosmium: .osm.pbf, .osm, .osm.gz,
// .osm.bz2; sorted by type or not) into what the bake needs:
// drivable streets as polylines and building footprints (closed ways and
// multipolygon relations, with inner rings) with their heights, all in the
// local ENU frame of the extract.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <glm/vec2.hpp>

#include "bake/triangulate.h"
#include "geo/local_frame.h"
#include "graph/street_graph.h"

namespace blvd::bake {

struct OsmStreet {
  int64_t way_id = 0;
  std::vector<int64_t> nodes;     // OSM node ids, one per point
  std::vector<glm::dvec2> pts;    // local east/north metres
  graph::RoadClass road_class = graph::RoadClass::Other;
  float width = 0;                // carriageway width, metres
  int8_t layer = 0;
  bool bridge = false, tunnel = false, oneway = false;
};

enum class HeightSource : uint8_t { Height, Levels, Default };

struct OsmBuilding {
  int64_t id = 0;                 // way id, or relation id for multipolygons
  bool from_way = true;
  bool is_part = false;           // building:part=*
  std::vector<Polygon2> polygons; // outer rings with their inner rings
  double height = 0, min_height = 0;
  HeightSource source = HeightSource::Default;
};

struct OsmReadOptions {
  // Stated and logged: a building with neither `height` nor `building:levels`
  // gets this height (4 levels of 3 m, typical of Monaco's older blocks).
  double default_height_m = 12.0;
  double level_height_m = 3.0;
};

struct OsmCity {
  double origin_lat = 0, origin_lon = 0;  // centre of the streets' bounding box
  std::vector<OsmStreet> streets;
  std::vector<OsmBuilding> buildings;
  uint64_t source_bytes = 0;
  // Statistics for the bake summary.
  size_t ways_read = 0, nodes_read = 0, relations_read = 0;
  size_t height_tagged = 0, level_tagged = 0, defaulted = 0, parts = 0, outlines_hidden_by_parts = 0;
  size_t bad_polygons = 0;        // footprints that could not be assembled or used
};

// Throws core::Error(Io) if the file cannot be read, core::Error(Corrupt) with
// the file name if libosmium rejects it, core::Error(NotFound) naming what is
// missing when the extract has no drivable street or no building.
// `progress(done, total)` gets bytes (total: twice the file, read twice).
OsmCity readOsm(const std::string& path, const OsmReadOptions& opt,
                const std::function<void(uint64_t, uint64_t)>& progress = {});

// Parses an OSM length: "12", "12.5 m", "40'", "40 ft", "3;4" (first value).
// Returns false for anything else.
bool parseLength(const char* s, double& metres);

// Drivable highway=* value -> class and default width; false if not drivable.
bool classifyHighway(const char* highway, const char* service, graph::RoadClass& cls, float& width);

}  // namespace blvd::bake
