// The half-edge invariants on both real Monaco extracts, and that every
// building lands in exactly one block, checked independently of CGAL's point
// location by winding numbers over each face's boundary cycles.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include <glm/common.hpp>

#include "bake/block_mesh.h"
#include "bake/osm_reader.h"
#include "bake/street_map.h"
#include "core/status.h"

using namespace blvd;

namespace {

struct Cycle {
  std::vector<glm::dvec2> pts;
  glm::dvec2 lo{1e30}, hi{-1e30};
};

// Winding number of closed polyline c around p.
int winding(const Cycle& c, glm::dvec2 p) {
  if (p.x < c.lo.x || p.y < c.lo.y || p.x > c.hi.x || p.y > c.hi.y) return 0;
  int w = 0;
  for (size_t i = 0, n = c.pts.size(); i < n; ++i) {
    const glm::dvec2 a = c.pts[i], b = c.pts[(i + 1) % n];
    const double cross = (b.x - a.x) * (p.y - a.y) - (p.x - a.x) * (b.y - a.y);
    if (a.y <= p.y) {
      if (b.y > p.y && cross > 0) ++w;
    } else if (b.y <= p.y && cross < 0) {
      --w;
    }
  }
  return w;
}

struct FaceCycles {
  Cycle outer;
  std::vector<Cycle> inner;
};

std::vector<FaceCycles> faceCycles(const graph::StreetGraph& g) {
  std::vector<FaceCycles> out(g.faces.size());
  std::vector<uint8_t> seen(g.halfedges.size(), 0);
  for (uint32_t h0 = 0; h0 < g.halfedges.size(); ++h0) {
    if (seen[h0]) continue;
    Cycle c;
    bool is_outer = false;
    uint32_t h = h0;
    do {
      seen[h] = 1;
      const auto& e = g.halfedges[h];
      is_outer |= g.faces[e.face].halfedge == h;
      for (uint32_t i = 0; i + 1 < e.pts_count; ++i) {
        const glm::dvec2 p = g.points[e.pts_begin + i];
        c.pts.push_back(p);
        c.lo = glm::min(c.lo, p);
        c.hi = glm::max(c.hi, p);
      }
      h = e.next;
    } while (h != h0);
    FaceCycles& fc = out[g.halfedges[h0].face];
    if (is_outer) fc.outer = std::move(c);
    else fc.inner.push_back(std::move(c));
  }
  return out;
}

bool inFace(const graph::StreetGraph& g, const FaceCycles& fc, uint32_t f, glm::dvec2 p) {
  if (!g.faces[f].unbounded && winding(fc.outer, p) == 0) return false;
  for (const Cycle& c : fc.inner)
    if (winding(c, p) != 0) return false;
  return true;
}

void checkCity(const std::string& file, size_t min_buildings) {
  bake::OsmReadOptions opt;
  const bake::OsmCity city = bake::readOsm(std::string(BLVD_DATA_DIR) + "/osm/" + file, opt);
  bake::StreetMap map(city.streets);
  const graph::StreetGraph& g = map.graph();
  const auto bad = graph::checkInvariants(g);
  ASSERT_TRUE(bad.empty()) << file << ": " << bad.front();
  // Euler, spelled out (checkInvariants includes it).
  const long long V = g.vertices.size(), E = g.halfedges.size() / 2, F = g.faces.size();
  EXPECT_EQ(V - E + F, 1 + static_cast<long long>(g.componentCount()));
  EXPECT_GT(g.junctionCount(), 200u);
  EXPECT_GT(F, 50);
  size_t crossings = 0;
  for (const auto& v : g.vertices) crossings += v.kind == graph::VertexKind::Crossing;
  ::testing::Test::RecordProperty("crossings", static_cast<int>(crossings));
  // Every cell but a few isolated ones continues somewhere.
  size_t stuck = 0;
  for (uint32_t h = 0; h < g.halfedges.size(); ++h) stuck += g.successors.count(h) == 0;
  EXPECT_LT(stuck, g.halfedges.size() / 20) << "cells with no successor";

  ASSERT_GE(city.buildings.size(), min_buildings);
  const auto cycles = faceCycles(g);
  size_t placed = 0;
  for (const bake::OsmBuilding& b : city.buildings) {
    glm::dvec2 p;
    if (!bake::buildingAnchor(b, p)) continue;
    ++placed;
    const uint32_t f = map.locateFace(p);
    size_t containing = 0;
    bool located_contains = false;
    for (uint32_t k = 0; k < g.faces.size(); ++k)
      if (inFace(g, cycles[k], k, p)) {
        ++containing;
        located_contains |= (k == f);
      }
    ASSERT_EQ(containing, 1u) << file << ": building " << b.id << " at (" << p.x << ", " << p.y << ")";
    ASSERT_TRUE(located_contains) << file << ": building " << b.id;
  }
  EXPECT_GT(placed, city.buildings.size() * 99 / 100);
}

}  // namespace

TEST(MonacoGraph, Geofabrik2026) { checkCity("monaco-geofabrik-2026.osm.pbf", 1500); }
TEST(MonacoGraph, Osrm2016) { checkCity("monaco-osrm-2016.osm.pbf", 20000); }

TEST(OsmReader, ParsesLengths) {
  double m = 0;
  EXPECT_TRUE(bake::parseLength("12", m));
  EXPECT_DOUBLE_EQ(m, 12);
  EXPECT_TRUE(bake::parseLength("12.5 m", m));
  EXPECT_DOUBLE_EQ(m, 12.5);
  EXPECT_TRUE(bake::parseLength("40'", m));
  EXPECT_NEAR(m, 12.192, 1e-9);
  EXPECT_TRUE(bake::parseLength("3;4", m));
  EXPECT_DOUBLE_EQ(m, 3);
  EXPECT_FALSE(bake::parseLength("tall", m));
  EXPECT_FALSE(bake::parseLength("", m));
}

TEST(OsmReader, MissingFileIsAnIoErrorNamingThePath) {
  try {
    bake::readOsm("/nonexistent/x.osm.pbf", {});
    FAIL();
  } catch (const core::Error& e) {
    EXPECT_EQ(e.status(), core::Status::Io);
    EXPECT_NE(std::string(e.what()).find("/nonexistent/x.osm.pbf"), std::string::npos);
  }
}

TEST(OsmReader, GarbageFileIsCorrupt) {
  const std::string path = std::string(BLVD_BINARY_DIR) + "/garbage.osm.pbf";
  FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_TRUE(f);
  std::fputs("this is not a protobuf file at all, just text\n", f);
  std::fclose(f);
  try {
    bake::readOsm(path, {});
    FAIL();
  } catch (const core::Error& e) {
    EXPECT_EQ(e.status(), core::Status::Corrupt);
    EXPECT_NE(std::string(e.what()).find("garbage.osm.pbf"), std::string::npos);
  }
}
