// A synthetic city baked on a synthetic DEM (SRTM tile N43E007 written by the
// test): a slope rising 5 % to the east, and a flat tile. On the slope the
// package's ELEV follows the ground under every street, nothing of a block
// sinks under it, buildings stand at the lowest ground under them, and the
// runtime's eye rides 1.5 m above the road. On the flat tile the frames are
// those of the flat bake (the ground is only split into more triangles).
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "bake/bake.h"
#include "blvd/blvd.h"
#include "capi/binding.h"
#include "common/osm_writer.h"
#include "imaging/image.h"
#include "stream/city.h"

namespace blvd {
namespace {

constexpr double kLat0 = 43.70, kLon0 = 7.40;
const double kMetresPerLon = 111320.0 * std::cos(kLat0 * M_PI / 180.0);

// The slope: metres above sea level at a longitude (5 m per 100 m east of kLon0).
double slope(double lon) { return 100.0 + 0.05 * (lon - kLon0) * kMetresPerLon; }

// An SRTM3 tile N43E007 whose samples are f(lat, lon), rounded to metres as SRTM's are.
template <class F>
void writeTile(const std::string& path, F f) {
  const int n = 1201;
  std::vector<uint8_t> b(size_t(n) * n * 2);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      const auto v = uint16_t(int16_t(std::lround(f(44.0 - double(r) / (n - 1), 7.0 + double(c) / (n - 1)))));
      b[(size_t(r) * n + c) * 2] = uint8_t(v >> 8);
      b[(size_t(r) * n + c) * 2 + 1] = uint8_t(v & 0xff);
    }
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));
}

// Three streets east-west, three north-south, 200 m apart; a building in
// each of two blocks.
std::string cityOsm() {
  test::OsmWriter w;
  std::vector<std::vector<int>> id(3, std::vector<int>(3));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) id[i][j] = w.node(200.0 * i, 200.0 * j);
  for (int j = 0; j < 3; ++j) w.way({id[0][j], id[1][j], id[2][j]}, "    <tag k=\"highway\" v=\"residential\"/>\n");
  for (int i = 0; i < 3; ++i) w.way({id[i][0], id[i][1], id[i][2]}, "    <tag k=\"highway\" v=\"residential\"/>\n");
  w.building(40, 40, 160, 80, 20);
  w.building(240, 120, 360, 170, 30);
  return w.str();
}

struct Baked {
  std::string package;
  stream::City city;
};

// The city baked without a DEM ("flat") or on the tile `tile` writes.
std::string bake(const std::string& name, const std::function<double(double, double)>& tile) {
  const std::string dir = std::string(BLVD_BINARY_DIR) + "/terrain_bake";
  ::mkdir(dir.c_str(), 0755);
  std::ofstream(dir + "/city.osm") << cityOsm();
  bake::BakeOptions o;
  o.quiet = true;
  o.impostor.mode = bake::ImpostorMode::None;
  if (tile) {
    ::mkdir((dir + "/" + name).c_str(), 0755);
    writeTile(dir + "/" + name + "/N43E007.hgt", tile);
    o.dem = {dir + "/" + name + "/N43E007.hgt"};
  }
  const std::string out = dir + "/" + name + ".blvd";
  bake::bakeCity(dir + "/city.osm", out, o);
  return out;
}

double lonOf(const stream::City& city, glm::dvec2 en) {
  double lat, lon, h;
  city.frame().reverse(geo::Enu{en.x, en.y, 0}, lat, lon, h);
  return lon;
}

TEST(TerrainBake, OnASlopeTheStreetsAndBlocksFollowTheGround) {
  stream::City city;
  std::string err;
  ASSERT_EQ(city.open(bake("slope", [](double, double lon) { return slope(lon); }), err), core::Status::Ok) << err;
  ASSERT_TRUE(city.hasGround());
  const graph::GraphSource& g = city.streets();
  // ELEV: every street point at the ground under it (SRTM's metre rounding
  // and its bilinear between samples: within 0.5 m).
  // Along each cell's polyline: at its points and halfway between them.
  for (uint32_t c = 0; c < g.cellCount(); ++c) {
    const graph::HalfEdge e = g.halfedge(c);
    double arc = 0;
    for (uint32_t i = 0; i < e.pts_count; ++i) {
      const glm::dvec2 a = g.point(e.pts_begin + i);
      EXPECT_NEAR(city.groundHeight(c, arc), slope(lonOf(city, a)), 0.5) << "cell " << c << " point " << i;
      if (i + 1 == e.pts_count) break;
      const glm::dvec2 b = g.point(e.pts_begin + i + 1);
      EXPECT_NEAR(city.groundHeight(c, arc + glm::length(b - a) / 2), slope(lonOf(city, (a + b) * 0.5)), 0.5);
      arc += glm::length(b - a);
    }
  }
  // Every surface that faces up (ground, streets, roofs) on or above the
  // ground (0.5 m for the DEM's rounding); walls start at the lowest ground
  // of their block, uphill walls below the ground (a building stands at the
  // lowest ground under it), none lower.
  size_t up = 0;
  for (uint32_t b = 0; b < city.blockCount(); ++b) {
    if (city.block(b).lod_count == 0) continue;
    geo::MeshData m;
    ASSERT_EQ(city.decodeBlock(b, 0, m, err), core::Status::Ok) << err;
    double lowest_ground = 1e9, lowest = 1e9;
    for (size_t v = 0; v < m.vertexCount(); ++v) {
      const double ground = slope(lonOf(city, {m.positions[3 * v], -m.positions[3 * v + 2]}));
      lowest_ground = std::min(lowest_ground, ground);
      lowest = std::min(lowest, double(m.positions[3 * v + 1]));
      if (m.normals[3 * v + 1] < 0.9) continue;
      ++up;
      ASSERT_GT(m.positions[3 * v + 1], ground - 0.5) << "block " << b << " vertex " << v;
    }
    EXPECT_GT(lowest, lowest_ground - 0.5) << "block " << b;
  }
  EXPECT_GT(up, 100u);
  // The runtime's eye: 1.5 m above the road at the pose.
  blvd_runtime_desc d{};
  d.struct_size = sizeof d;
  const std::string path = std::string(BLVD_BINARY_DIR) + "/terrain_bake/slope.blvd";
  d.package_path = path.c_str();
  d.width = 160, d.height = 96;
  blvd_runtime* rt = nullptr;
  ASSERT_EQ(blvd_runtime_create(&d, &rt), BLVD_OK) << blvd_last_error(nullptr);
  // On a street running east (uphill), facing east: the eye 1.5 m above the
  // road and the camera pitched up with the road's 5 % grade.
  uint32_t east = graph::kNone;
  for (uint32_t c = 0; c < g.cellCount() && east == graph::kNone; ++c) {
    const graph::HalfEdge e = g.halfedge(c);
    const glm::dvec2 run = g.point(e.pts_begin + 1) - g.point(e.pts_begin);
    if (e.pts_count >= 2 && run.x > 100 && std::abs(run.y) < 1) east = c;
  }
  ASSERT_NE(east, graph::kNone);
  const glm::dvec2 p = g.point(g.halfedge(east).pts_begin) * 0.5 + g.point(g.halfedge(east).pts_begin + 1) * 0.5;
  ASSERT_EQ(blvd_set_pose_local(rt, p.x, p.y, 90.f, 0.f), BLVD_OK);
  ASSERT_EQ(blvd_wait_resident(rt, 60000), BLVD_OK) << blvd_last_error(rt);
  blvd_frame_stats fs{};
  fs.struct_size = sizeof fs;
  ASSERT_EQ(blvd_render(rt, &fs), BLVD_OK) << blvd_last_error(rt);
  EXPECT_EQ(fs.cell, east);
  EXPECT_NEAR(rt->impl->camera().eye_enu.z, slope(lonOf(city, p)) + 1.5, 0.6);
  EXPECT_NEAR(rt->impl->camera().pitch_deg, std::atan(0.05) * 180.0 / M_PI, 0.5);
  // The tracker's pose there (a start pose on that street) carries the same camera.
  blvd_start_pose sp{};
  sp.struct_size = sizeof sp;
  sp.t = 100;
  double h;
  city.frame().reverse(geo::Enu{p.x, p.y, 0}, sp.lat, sp.lon, h);
  sp.heading_deg = 90;
  ASSERT_EQ(blvd_set_start_pose(rt, &sp), BLVD_OK) << blvd_last_error(rt);
  blvd_pose pose{};
  pose.struct_size = sizeof pose;
  ASSERT_EQ(blvd_get_pose(rt, 100, &pose), BLVD_OK) << blvd_last_error(rt);
  ASSERT_TRUE(pose.flags & BLVD_POSE_MATCHED) << pose.flags;
  EXPECT_NEAR(pose.camera_z, slope(lonOf(city, p)) + 1.5, 0.6);
  EXPECT_NEAR(pose.camera_pitch_deg, std::atan(0.05) * 180.0 / M_PI, 0.5);
  blvd_runtime_destroy(rt);
}

// A frame at `pose` (east, north, heading) of a package: RGBA, 320 x 192.
std::vector<uint8_t> frameOf(const std::string& package, glm::dvec3 pose) {
  blvd_runtime_desc d{};
  d.struct_size = sizeof d;
  d.package_path = package.c_str();
  d.width = 320, d.height = 192;
  blvd_runtime* rt = nullptr;
  EXPECT_EQ(blvd_runtime_create(&d, &rt), BLVD_OK) << blvd_last_error(nullptr);
  std::vector<uint8_t> px(size_t(d.width) * d.height * 4);
  if (!rt) return px;
  EXPECT_EQ(blvd_set_pose_local(rt, pose.x, pose.y, float(pose.z), 0.f), BLVD_OK);
  EXPECT_EQ(blvd_wait_resident(rt, 60000), BLVD_OK) << blvd_last_error(rt);
  blvd_frame_stats fs{};
  fs.struct_size = sizeof fs;
  EXPECT_EQ(blvd_render(rt, &fs), BLVD_OK) << blvd_last_error(rt);
  EXPECT_EQ(blvd_read_pixels(rt, px.data(), px.size()), BLVD_OK) << blvd_last_error(rt);
  blvd_runtime_destroy(rt);
  return px;
}

TEST(TerrainBake, AFlatDemDrawsTheFlatBakesFrames) {
  const std::string flat = bake("flat", nullptr), zero = bake("zero", [](double, double) { return 0.0; });
  stream::City city;
  std::string err;
  ASSERT_EQ(city.open(zero, err), core::Status::Ok) << err;
  const glm::dvec2 p = city.streets().point(city.streets().halfedge(2).pts_begin);
  for (const double heading : {0.0, 90.0, 225.0}) {
    const std::vector<uint8_t> a = frameOf(flat, {p.x + 20, p.y, heading}), b = frameOf(zero, {p.x + 20, p.y, heading});
    EXPECT_GT(imaging::psnr(a.data(), b.data(), a.size() / 4), 40.0) << "heading " << heading;
  }
}

}  // namespace
}  // namespace blvd
