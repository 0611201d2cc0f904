#include "bake/osm_reader.h"

#include <sys/stat.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>

#include <osmium/area/assembler.hpp>
#include <osmium/area/multipolygon_manager.hpp>
#include <osmium/handler.hpp>
#include <osmium/handler/node_locations_for_ways.hpp>
#include <osmium/index/map/flex_mem.hpp>
#include <osmium/io/any_input.hpp>
#include <osmium/relations/relations_manager.hpp>
#include <osmium/visitor.hpp>

#include "core/log.h"
#include "core/status.h"

namespace blvd::bake {
namespace {

struct LonLatRing {
  std::vector<glm::dvec2> ll;
};
struct LonLatPolygon {
  LonLatRing outer;
  std::vector<LonLatRing> inners;
};
struct RawBuilding {
  OsmBuilding b;
  std::vector<LonLatPolygon> polys;
};
struct RawStreet {
  OsmStreet s;
  std::vector<glm::dvec2> ll;
};

class Collector : public osmium::handler::Handler {
 public:
  explicit Collector(const OsmReadOptions& opt) : opt_(opt) {}
  std::vector<RawStreet> streets;
  std::vector<RawBuilding> buildings;
  size_t ways = 0, nodes = 0, relations = 0, bad = 0;

  void node(const osmium::Node&) { ++nodes; }
  void relation(const osmium::Relation&) { ++relations; }

  void way(const osmium::Way& w) {
    ++ways;
    const char* hw = w.tags()["highway"];
    if (!hw) return;
    if (w.tags().has_tag("area", "yes")) return;
    RawStreet rs;
    if (!classifyHighway(hw, w.tags()["service"], rs.s.road_class, rs.s.width)) return;
    double width = 0;
    if (const char* wt = w.tags()["width"]; wt && parseLength(wt, width) && width > 2 && width < 60)
      rs.s.width = static_cast<float>(width);
    rs.s.way_id = w.id();
    if (const char* l = w.tags()["layer"]) rs.s.layer = static_cast<int8_t>(std::max(-5, std::min(5, std::atoi(l))));
    const char* br = w.tags()["bridge"];
    const char* tu = w.tags()["tunnel"];
    rs.s.bridge = br && std::strcmp(br, "no") != 0;
    rs.s.tunnel = tu && std::strcmp(tu, "no") != 0;
    const char* ow = w.tags()["oneway"];
    rs.s.oneway = (ow && (!std::strcmp(ow, "yes") || !std::strcmp(ow, "1"))) || rs.s.road_class == graph::RoadClass::Motorway;
    for (const osmium::NodeRef& nr : w.nodes()) {
      if (!nr.location().valid()) continue;  // node missing from the extract (clipped)
      if (!rs.ll.empty() && rs.s.nodes.back() == nr.ref()) continue;
      rs.s.nodes.push_back(nr.ref());
      rs.ll.emplace_back(nr.location().lon(), nr.location().lat());
    }
    if (rs.ll.size() >= 2) streets.push_back(std::move(rs));
  }

  void area(const osmium::Area& a) {
    const bool is_building = a.tags().has_key("building") && !a.tags().has_tag("building", "no");
    const bool is_part = a.tags().has_key("building:part") && !a.tags().has_tag("building:part", "no");
    if (!is_building && !is_part) return;
    RawBuilding rb;
    rb.b.id = a.orig_id();
    rb.b.from_way = a.from_way();
    rb.b.is_part = is_part && !is_building;
    double h = 0, minh = 0, levels = 0;
    if (const char* v = a.tags()["height"]; v && parseLength(v, h) && h > 0 && h < 1000) {
      rb.b.height = h;
      rb.b.source = HeightSource::Height;
    } else if (const char* lv = a.tags()["building:levels"]; lv && parseLength(lv, levels) && levels > 0 && levels < 300) {
      rb.b.height = levels * opt_.level_height_m;
      rb.b.source = HeightSource::Levels;
    } else {
      rb.b.height = opt_.default_height_m;
      rb.b.source = HeightSource::Default;
    }
    if (const char* v = a.tags()["min_height"]; v && parseLength(v, minh) && minh >= 0) {
      rb.b.min_height = minh;
    } else if (const char* ml = a.tags()["building:min_level"]; ml && parseLength(ml, levels) && levels > 0) {
      rb.b.min_height = levels * opt_.level_height_m;
    }
    if (rb.b.min_height >= rb.b.height) rb.b.min_height = 0;  // inconsistent tags: keep the building, drop min_height
    for (const osmium::OuterRing& outer : a.outer_rings()) {
      LonLatPolygon p;
      for (const osmium::NodeRef& nr : outer) p.outer.ll.emplace_back(nr.location().lon(), nr.location().lat());
      for (const osmium::InnerRing& inner : a.inner_rings(outer)) {
        LonLatRing r;
        for (const osmium::NodeRef& nr : inner) r.ll.emplace_back(nr.location().lon(), nr.location().lat());
        p.inners.push_back(std::move(r));
      }
      rb.polys.push_back(std::move(p));
    }
    if (rb.polys.empty()) {
      ++bad;
      return;
    }
    buildings.push_back(std::move(rb));
  }

 private:
  const OsmReadOptions& opt_;
};

Ring toRing(const LonLatRing& r, const geo::LocalFrame& f) {
  Ring out;
  out.pts.reserve(r.ll.size());
  for (const glm::dvec2& ll : r.ll) {
    geo::Enu e = f.forward(ll.y, ll.x);
    out.pts.emplace_back(e.e, e.n);
  }
  if (out.pts.size() > 1 && out.pts.front() == out.pts.back()) out.pts.pop_back();  // closed implicitly
  return out;
}

bool pointInRing(const glm::dvec2& p, const Ring& r) {
  bool in = false;
  for (size_t i = 0, j = r.pts.size() - 1; i < r.pts.size(); j = i++) {
    const glm::dvec2 &a = r.pts[i], &b = r.pts[j];
    if ((a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x) in = !in;
  }
  return in;
}

glm::dvec2 ringCentroid(const Ring& r) {
  glm::dvec2 c(0);
  for (const auto& p : r.pts) c += p;
  return r.pts.empty() ? c : c / double(r.pts.size());
}

// Simple 3D Buildings convention: when building:part areas exist inside a
// building outline, the parts describe the building and the outline is not drawn.
size_t hideOutlinesWithParts(std::vector<OsmBuilding>& bs) {
  std::vector<size_t> parts, outlines;
  for (size_t i = 0; i < bs.size(); ++i) (bs[i].is_part ? parts : outlines).push_back(i);
  if (parts.empty()) return 0;
  std::vector<bool> hide(bs.size(), false);
  for (size_t oi : outlines) {
    for (size_t pi : parts) {
      const OsmBuilding& part = bs[pi];
      if (part.polygons.empty() || part.polygons[0].outer.pts.empty()) continue;
      const glm::dvec2 c = ringCentroid(part.polygons[0].outer);
      for (const Polygon2& poly : bs[oi].polygons)
        if (pointInRing(c, poly.outer)) hide[oi] = true;
      if (hide[oi]) break;
    }
  }
  std::vector<OsmBuilding> kept;
  size_t hidden = 0;
  for (size_t i = 0; i < bs.size(); ++i) {
    if (hide[i]) ++hidden;
    else kept.push_back(std::move(bs[i]));
  }
  bs = std::move(kept);
  return hidden;
}

}  // namespace

bool parseLength(const char* s, double& metres) {
  if (!s) return false;
  char* end = nullptr;
  const double v = std::strtod(s, &end);
  if (end == s || !std::isfinite(v)) return false;
  while (*end == ' ') ++end;
  if (*end == 0 || *end == ';' || !std::strcmp(end, "m")) {
    metres = v;
    return true;
  }
  if (*end == '\'' || !std::strncmp(end, "ft", 2)) {
    metres = v * 0.3048;
    return true;
  }
  return false;
}

bool classifyHighway(const char* hw, const char* service, graph::RoadClass& cls, float& width) {
  using graph::RoadClass;
  struct Row { const char* tag; RoadClass cls; float width; };
  static const Row rows[] = {
      {"motorway", RoadClass::Motorway, 14.f},      {"trunk", RoadClass::Trunk, 12.f},
      {"primary", RoadClass::Primary, 11.f},        {"secondary", RoadClass::Secondary, 10.f},
      {"tertiary", RoadClass::Tertiary, 9.f},       {"unclassified", RoadClass::Unclassified, 7.f},
      {"residential", RoadClass::Residential, 7.f}, {"living_street", RoadClass::LivingStreet, 6.f},
      {"service", RoadClass::Service, 4.5f},        {"road", RoadClass::Other, 7.f},
      {"motorway_link", RoadClass::Link, 7.f},      {"trunk_link", RoadClass::Link, 7.f},
      {"primary_link", RoadClass::Link, 7.f},       {"secondary_link", RoadClass::Link, 6.5f},
      {"tertiary_link", RoadClass::Link, 6.f},
  };
  for (const Row& r : rows) {
    if (std::strcmp(hw, r.tag) != 0) continue;
    // Parking aisles and driveways are private access lanes, not streets: they
    // would cut blocks into slivers.
    if (r.cls == RoadClass::Service && service &&
        (!std::strcmp(service, "parking_aisle") || !std::strcmp(service, "driveway") ||
         !std::strcmp(service, "drive-through")))
      return false;
    cls = r.cls;
    width = r.width;
    return true;
  }
  return false;
}

// libosmium 2.19's PBF parser reads the file's descriptor itself and closes
// it only after a read that succeeds (PBFParser::run): every corrupt PBF
// would leak a descriptor (found by fuzz_osm, which ran out of them). A PBF
// is therefore read into memory and parsed from there, where no descriptor is
// involved; other formats go through a decompressor that closes its own.
// The cost: the file's size in memory while it is read (its passes report
// progress whole).
osmium::io::File osmFile(const std::string& path, std::string& bytes) {
  osmium::io::File file{path};
  if (file.format() != osmium::io::file_format::pbf || file.compression() != osmium::io::file_compression::none)
    return file;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw core::Error(core::Status::Io, path + ": cannot open (" + std::strerror(errno) + ")");
  char chunk[1 << 16];
  size_t n = 0;
  while ((n = std::fread(chunk, 1, sizeof chunk, f)) > 0) bytes.append(chunk, n);
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed) throw core::Error(core::Status::Io, path + ": read error after " + std::to_string(bytes.size()) + " bytes");
  return osmium::io::File{bytes.data(), bytes.size(), "pbf"};
}

OsmCity readOsm(const std::string& path, const OsmReadOptions& opt,
                const std::function<void(uint64_t, uint64_t)>& progress) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) throw core::Error(core::Status::Io, path + ": cannot open (" + std::strerror(errno) + ")");
  OsmCity city;
  city.source_bytes = static_cast<uint64_t>(st.st_size);
  Collector col(opt);
  try {
    // .osm.pbf, .osm, and either compressed with gzip or bzip2 (libosmium
    // picks the format from the name). Three passes: relations (the
    // multipolygon buildings' members), nodes, then ways. Reading nodes on a
    // pass of their own lets an extract that is not sorted by type (a way
    // before its nodes) bake exactly as its sorted copy does.
    std::string bytes;  // a PBF's contents (osmFile)
    const osmium::io::File file = osmFile(path, bytes);
    osmium::area::Assembler::config_type acfg;
    osmium::TagsFilter filter{false};
    filter.add_rule(true, "building");
    filter.add_rule(true, "building:part");
    osmium::area::MultipolygonManager<osmium::area::Assembler> mp{acfg, filter};
    osmium::relations::read_relations(file, mp);

    using Index = osmium::index::map::FlexMem<osmium::unsigned_object_id_type, osmium::Location>;
    Index index;
    osmium::handler::NodeLocationsForWays<Index> locations{index};
    locations.ignore_errors();  // clipped extracts reference nodes they do not hold
    const auto pass = [&](osmium::osm_entity_bits::type entities, uint64_t done_before) {
      osmium::io::Reader reader{file, entities};
      while (osmium::memory::Buffer buffer = reader.read()) {
        osmium::apply(buffer, locations, col, mp.handler([&col](osmium::memory::Buffer&& area_buffer) {
          osmium::apply(area_buffer, col);
        }));
        if (progress) progress(done_before + reader.offset(), 2 * city.source_bytes);
      }
      reader.close();
    };
    pass(osmium::osm_entity_bits::node, 0);
    pass(osmium::osm_entity_bits::way | osmium::osm_entity_bits::relation, city.source_bytes);
    city.bad_polygons = col.bad + mp.stats().area_really_complex_case;
  } catch (const core::Error&) {
    throw;
  } catch (const std::exception& e) {
    throw core::Error(core::Status::Corrupt, path + ": " + e.what());
  }
  if (col.streets.empty())
    throw core::Error(core::Status::NotFound, path + ": no drivable street (highway=* way) in the extract: nothing to drive on");
  if (col.buildings.empty())
    throw core::Error(core::Status::NotFound, path + ": no building (building=* way or multipolygon) in the extract: nothing to render");

  // Origin: centre of the streets' bounding box, on the ellipsoid.
  double lo_lon = 1e9, lo_lat = 1e9, hi_lon = -1e9, hi_lat = -1e9;
  for (const RawStreet& s : col.streets)
    for (const glm::dvec2& ll : s.ll) {
      lo_lon = std::min(lo_lon, ll.x), hi_lon = std::max(hi_lon, ll.x);
      lo_lat = std::min(lo_lat, ll.y), hi_lat = std::max(hi_lat, ll.y);
    }
  city.origin_lat = 0.5 * (lo_lat + hi_lat);
  city.origin_lon = 0.5 * (lo_lon + hi_lon);
  const geo::LocalFrame frame(city.origin_lat, city.origin_lon, 0);

  city.streets.reserve(col.streets.size());
  for (RawStreet& rs : col.streets) {
    for (const glm::dvec2& ll : rs.ll) {
      geo::Enu e = frame.forward(ll.y, ll.x);
      rs.s.pts.emplace_back(e.e, e.n);
    }
    city.streets.push_back(std::move(rs.s));
  }
  for (RawBuilding& rb : col.buildings) {
    for (const LonLatPolygon& p : rb.polys) {
      Polygon2 poly;
      poly.outer = toRing(p.outer, frame);
      for (const LonLatRing& r : p.inners) poly.inners.push_back(toRing(r, frame));
      rb.b.polygons.push_back(std::move(poly));
    }
    switch (rb.b.source) {
      case HeightSource::Height: ++city.height_tagged; break;
      case HeightSource::Levels: ++city.level_tagged; break;
      case HeightSource::Default: ++city.defaulted; break;
    }
    if (rb.b.is_part) ++city.parts;
    city.buildings.push_back(std::move(rb.b));
  }
  city.outlines_hidden_by_parts = hideOutlinesWithParts(city.buildings);
  city.ways_read = col.ways;
  city.nodes_read = col.nodes;
  city.relations_read = col.relations;
  BLVD_LOG_INFO("%s: %zu streets, %zu buildings (%zu with height, %zu with levels, %zu at the default %.1f m), "
                "%zu parts hid %zu outlines",
                path.c_str(), city.streets.size(), city.buildings.size(), city.height_tagged, city.level_tagged,
                city.defaulted, opt.default_height_m, city.parts, city.outlines_hidden_by_parts);
  return city;
}

}  // namespace blvd::bake
