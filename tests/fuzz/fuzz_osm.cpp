// Fuzz target for the bake's OSM reader (bake/osm_reader: libosmium's XML and
// PBF parsers, the multipolygon assembler, the street and building filters).
// The input is read twice, as an .osm (XML) file and as an .osm.pbf file: each
// read ends in a city or in a core::Error whose message names the file, never
// a crash or another exception; what it gives is finite and in the extract's
// frame.
//
// Seeds: set BLVD_FUZZ_SEED_DIR and the target writes a small XML extract and
// its PBF there (a street, a building way, a multipolygon with a hole).
// (Monaco's PBF is 600 kB: too big a seed for a fuzzer's mutations.)
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include <osmium/io/any_input.hpp>
#include <osmium/io/any_output.hpp>

#include "bake/osm_reader.h"
#include "core/log.h"
#include "core/status.h"

namespace {

using blvd::bake::OsmCity;

// One scratch folder per process, removed at exit (a plain array: no destructor).
const char* tempDir() {
  static char dir[4096] = {};
  if (!dir[0]) {
    const std::string tmpl = (std::filesystem::temp_directory_path() / "blvd_fuzz_osm_XXXXXX").string();
    if (tmpl.size() >= sizeof dir) std::abort();
    std::memcpy(dir, tmpl.c_str(), tmpl.size() + 1);
    if (!::mkdtemp(dir)) std::abort();
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(dir, ec);
    });
  }
  return dir;
}

void checkCity(const OsmCity& c) {
  if (!std::isfinite(c.origin_lat) || !std::isfinite(c.origin_lon)) std::abort();
  for (const auto& s : c.streets) {
    if (s.pts.size() != s.nodes.size() || s.pts.size() < 2) std::abort();
    for (const auto& p : s.pts)
      if (!std::isfinite(p.x) || !std::isfinite(p.y)) std::abort();
  }
  for (const auto& b : c.buildings) {
    if (b.polygons.empty() || !(b.height > 0) || !std::isfinite(b.height) || !(b.min_height >= 0)) std::abort();
    for (const auto& poly : b.polygons)
      for (const auto& p : poly.outer.pts)
        if (!std::isfinite(p.x) || !std::isfinite(p.y)) std::abort();
  }
}

void readAs(const uint8_t* data, size_t size, const char* name) {
  const std::string path = std::string(tempDir()) + "/" + name;
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f || (size && std::fwrite(data, 1, size, f) != size)) std::abort();
  std::fclose(f);
  try {
    checkCity(blvd::bake::readOsm(path, {}));
  } catch (const blvd::core::Error& e) {
    if (std::string(e.what()).find(name) == std::string::npos) {
      std::fprintf(stderr, "error without the file's name: %s\n", e.what());
      std::abort();
    }
  }
  // Anything else escapes and libFuzzer reports it as a crash.
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  blvd::core::setLogLevel(blvd::core::LogLevel::Error);
  const char* dir = std::getenv("BLVD_FUZZ_SEED_DIR");
  if (!dir || !*dir) return 0;
  std::filesystem::create_directories(dir);
  std::ofstream f(std::filesystem::path(dir) / "small.osm", std::ios::binary | std::ios::trunc);
  f << R"(<?xml version="1.0" encoding="UTF-8"?>
<osm version="0.6" generator="blvd fuzz seed">
 <node id="1" lat="43.7380" lon="7.4200"/>
 <node id="2" lat="43.7390" lon="7.4210"/>
 <node id="3" lat="43.7384" lon="7.4204"/>
 <node id="4" lat="43.7384" lon="7.4206"/>
 <node id="5" lat="43.7386" lon="7.4206"/>
 <node id="6" lat="43.7386" lon="7.4204"/>
 <node id="7" lat="43.7381" lon="7.4207"/>
 <node id="8" lat="43.7381" lon="7.4209"/>
 <node id="9" lat="43.7383" lon="7.4209"/>
 <node id="10" lat="43.7383" lon="7.4207"/>
 <node id="11" lat="43.73815" lon="7.42075"/>
 <node id="12" lat="43.73815" lon="7.42085"/>
 <node id="13" lat="43.73825" lon="7.42085"/>
 <node id="14" lat="43.73825" lon="7.42075"/>
 <way id="100"><nd ref="1"/><nd ref="2"/><tag k="highway" v="residential"/><tag k="oneway" v="yes"/><tag k="width" v="7 m"/></way>
 <way id="101"><nd ref="3"/><nd ref="4"/><nd ref="5"/><nd ref="6"/><nd ref="3"/><tag k="building" v="yes"/><tag k="building:levels" v="5"/></way>
 <way id="102"><nd ref="7"/><nd ref="8"/><nd ref="9"/><nd ref="10"/><nd ref="7"/></way>
 <way id="103"><nd ref="11"/><nd ref="12"/><nd ref="13"/><nd ref="14"/><nd ref="11"/></way>
 <relation id="200"><member type="way" ref="102" role="outer"/><member type="way" ref="103" role="inner"/><tag k="type" v="multipolygon"/><tag k="building" v="yes"/><tag k="height" v="40'"/></relation>
</osm>
)";
  f.close();
  // The same extract as PBF, through libosmium's writer.
  osmium::io::Reader reader{(std::filesystem::path(dir) / "small.osm").string()};
  osmium::io::Header header;
  osmium::io::Writer writer{(std::filesystem::path(dir) / "small.osm.pbf").string(), header,
                            osmium::io::overwrite::allow};
  while (osmium::memory::Buffer buffer = reader.read()) writer(std::move(buffer));
  writer.close();
  reader.close();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  readAs(data, size, "fuzz.osm");
  readAs(data, size, "fuzz.osm.pbf");
  return 0;
}
