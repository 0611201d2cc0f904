// A small OpenStreetMap XML writer for tests that bake synthetic cities: nodes
// placed in metres east (x) and north (y) of an origin, streets, box
// buildings, and multipolygon buildings with inner rings. `str()` writes the
// file sorted by type as OSM files are (nodes, ways, relations);
// `unsortedStr()` writes the same elements relations first and nodes last.
#pragma once

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec4.hpp>

namespace blvd::test {

struct OsmWriter {
  double lat0 = 43.70, lon0 = 7.40;
  std::string nodes, ways, relations;
  int next_node = 1, next_way = 1, next_relation = 1;

  int node(double x, double y) {
    const double lat = lat0 + y / 111320.0, lon = lon0 + x / (111320.0 * std::cos(lat0 * M_PI / 180.0));
    char b[160];
    std::snprintf(b, sizeof b, "  <node id=\"%d\" version=\"1\" lat=\"%.8f\" lon=\"%.8f\"/>\n", next_node, lat, lon);
    nodes += b;
    return next_node++;
  }
  int way(const std::vector<int>& ids, const std::string& tags) {
    ways += "  <way id=\"" + std::to_string(next_way) + "\" version=\"1\">\n";
    for (int id : ids) ways += "    <nd ref=\"" + std::to_string(id) + "\"/>\n";
    ways += tags + "  </way>\n";
    return next_way++;
  }
  void street(const std::vector<glm::dvec2>& pts, std::vector<int>* ids = nullptr,
              const char* highway = "residential") {
    std::vector<int> v;
    for (glm::dvec2 p : pts) v.push_back(node(p.x, p.y));
    way(v, std::string("    <tag k=\"highway\" v=\"") + highway + "\"/>\n");
    if (ids) *ids = v;
  }
  // A closed ring of box corners, untagged (a multipolygon member) or with tags.
  int ring(double x0, double y0, double x1, double y1, const std::string& tags = "") {
    const int a = node(x0, y0), b = node(x1, y0), c = node(x1, y1), d = node(x0, y1);
    return way({a, b, c, d, a}, tags);
  }
  void building(double x0, double y0, double x1, double y1, double height) {
    ring(x0, y0, x1, y1, "    <tag k=\"building\" v=\"yes\"/>\n    <tag k=\"height\" v=\"" + std::to_string(height) +
                             "\"/>\n");
  }
  // A building=* multipolygon: one outer box with inner boxes (courtyards).
  void courtyardBuilding(double x0, double y0, double x1, double y1, const std::vector<glm::dvec4>& inner,
                         double height) {
    const int outer = ring(x0, y0, x1, y1);
    std::vector<int> inners;
    for (const glm::dvec4& r : inner) inners.push_back(ring(r.x, r.y, r.z, r.w));
    relations += "  <relation id=\"" + std::to_string(next_relation++) + "\" version=\"1\">\n";
    relations += "    <member type=\"way\" ref=\"" + std::to_string(outer) + "\" role=\"outer\"/>\n";
    for (int id : inners) relations += "    <member type=\"way\" ref=\"" + std::to_string(id) + "\" role=\"inner\"/>\n";
    relations += "    <tag k=\"type\" v=\"multipolygon\"/>\n    <tag k=\"building\" v=\"yes\"/>\n"
                 "    <tag k=\"height\" v=\"" + std::to_string(height) + "\"/>\n  </relation>\n";
  }
  std::string str() const { return head() + nodes + ways + relations + "</osm>\n"; }
  std::string unsortedStr() const { return head() + relations + ways + nodes + "</osm>\n"; }

 private:
  static std::string head() {
    return "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<osm version=\"0.6\" generator=\"blvd test\">\n";
  }
};

}  // namespace blvd::test
