#pragma once
#include <vector>

#include <glm/vec2.hpp>

#include "bake/osm_reader.h"

namespace blvd::test {

inline bake::OsmStreet street(int64_t id, std::vector<int64_t> nodes, std::vector<glm::dvec2> pts,
                              int8_t layer = 0) {
  bake::OsmStreet s;
  s.way_id = id;
  s.nodes = std::move(nodes);
  s.pts = std::move(pts);
  s.road_class = graph::RoadClass::Residential;
  s.width = 7;
  s.layer = layer;
  s.bridge = layer > 0;
  return s;
}

}  // namespace blvd::test
