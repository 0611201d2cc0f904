// A synthetic city baked on a synthetic DEM (SRTM tile N43E007 written by the
// test): a slope rising 5 % to the east, and a flat tile. On the slope the
// package's ELEV follows the ground under every street, nothing of a block
// sinks under it, buildings stand at the lowest ground under them, and the
// runtime's eye rides 1.5 m above the road. On the flat tile the frames are
// those of the flat bake (the ground is only split into more triangles).
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <glm/geometric.hpp>

#include "bake/bake.h"
#include "blvd/blvd.h"
#include "capi/binding.h"
#include "cli/malloc_probe.h"
#include "common/osm_writer.h"
#include "imaging/image.h"
#include "remote/servers.h"
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

// The running test's own directory: CTest runs the tests of this binary as
// processes side by side, and two baking the same package into one place
// read each other's half-written files.
std::string testDir() {
  const std::string dir =
      std::string(BLVD_BINARY_DIR) + "/terrain_bake/" + ::testing::UnitTest::GetInstance()->current_test_info()->name();
  std::filesystem::create_directories(dir);
  return dir;
}

// The city baked without a DEM ("flat") or on the tile `tile` writes.
std::string bake(const std::string& name, const std::function<double(double, double)>& tile) {
  const std::string dir = testDir();
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
  const std::string path = testDir() + "/slope.blvd";
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
  // A tracker without a renderer on the same package: the same camera.
  blvd_tracker_desc td{};
  td.struct_size = sizeof td;
  td.package_path = path.c_str();
  blvd_tracker* tr = nullptr;
  ASSERT_EQ(blvd_tracker_create(&td, &tr), BLVD_OK) << blvd_tracker_last_error(nullptr);
  ASSERT_EQ(blvd_tracker_set_start_pose(tr, &sp), BLVD_OK) << blvd_tracker_last_error(tr);
  blvd_pose alone{};
  alone.struct_size = sizeof alone;
  ASSERT_EQ(blvd_tracker_get_pose(tr, 100, &alone), BLVD_OK) << blvd_tracker_last_error(tr);
  ASSERT_TRUE(alone.flags & BLVD_POSE_MATCHED) << alone.flags;
  EXPECT_NEAR(alone.camera_z, pose.camera_z, 1e-6);
  EXPECT_NEAR(alone.camera_pitch_deg, pose.camera_pitch_deg, 1e-6);
  blvd_tracker_destroy(tr);
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

// A hill 300 m high, its top 1.2 km east of the city's east edge, and level
// ground (at sea level) elsewhere: outside every block, so only the terrain
// tiles can draw it.
constexpr double kHillEastM = 1600, kHillNorthM = 200;
double hill(double lat, double lon) {
  const double e = (lon - kLon0) * kMetresPerLon - kHillEastM, n = (lat - kLat0) * 111320.0 - kHillNorthM;
  return 300.0 * std::exp(-(e * e + n * n) / (2 * 350.0 * 350.0));
}

struct Frame {
  std::vector<uint8_t> px;
  blvd_stats stats{};
};

// Frames along the north street at heading `heading`, east from x = 60 m,
// the last one's pixels and the runtime's stats; `allocations` (optional):
// blvd's own on this thread over the frames after the first ten.
Frame driveNorthStreet(const std::string& package, float heading, long* allocations = nullptr,
                       const char* cache = nullptr) {
  blvd_runtime_desc d{};
  d.struct_size = sizeof d;
  d.package_path = package.c_str();
  d.cache_path = cache;
  d.width = 320, d.height = 192;
  blvd_runtime* rt = nullptr;
  Frame f;
  EXPECT_EQ(blvd_runtime_create(&d, &rt), BLVD_OK) << blvd_last_error(nullptr);
  if (!rt) return f;
  f.px.resize(size_t(d.width) * d.height * 4);
  std::unique_ptr<probe::ThreadMallocCounter> counter;
  for (int i = 0; i < 40; ++i) {
    if (i == 10 && allocations) counter = std::make_unique<probe::ThreadMallocCounter>();
    EXPECT_EQ(blvd_set_pose_local(rt, 60.0 + 3.0 * i, 400.0, heading, 0.f), BLVD_OK);
    if (i == 0) {
      EXPECT_EQ(blvd_wait_resident(rt, 60000), BLVD_OK) << blvd_last_error(rt);
    }
    EXPECT_EQ(blvd_render(rt, nullptr), BLVD_OK) << blvd_last_error(rt);
    if (cache && i == 0) {  // over the link: frames at the first pose until the tiles came (at most 30 s)
      blvd_stats st{};
      st.struct_size = sizeof st;
      for (int k = 0; k < 600 && blvd_runtime_stats(rt, &st) == BLVD_OK && st.terrain_loads < 8; ++k) {
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
        EXPECT_EQ(blvd_render(rt, nullptr), BLVD_OK) << blvd_last_error(rt);
      }
    }
  }
  if (counter) *allocations = counter->count();
  EXPECT_EQ(blvd_read_pixels(rt, f.px.data(), f.px.size()), BLVD_OK) << blvd_last_error(rt);
  f.stats.struct_size = sizeof f.stats;
  EXPECT_EQ(blvd_runtime_stats(rt, &f.stats), BLVD_OK);
  blvd_runtime_destroy(rt);
  return f;
}

// Pixels of the band 5 to 15 degrees above the horizon (the view's middle
// row at pitch 0) that differ between two frames by more than 12 in a channel
// (a hill 1.3 km off is mostly fog).
size_t differingAboveTheHorizon(const Frame& a, const Frame& b) {
  const int w = 320, h = 192;
  const double px_per_deg = h / 45.0;
  size_t n = 0;
  for (int y = int(h / 2 - 15 * px_per_deg); y < int(h / 2 - 5 * px_per_deg); ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c)
        if (std::abs(int(a.px[(size_t(y) * w + x) * 4 + c]) - int(b.px[(size_t(y) * w + x) * 4 + c])) > 12) {
          ++n;
          break;
        }
  return n;
}

TEST(TerrainBake, TheHillsBeyondTheCityAreDrawnFromStreamedTiles) {
  const std::string hilly = bake("hill", hill), flat = bake("flat", nullptr);
  stream::City city;
  std::string err;
  ASSERT_EQ(city.open(hilly, err), core::Status::Ok) << err;
  ASSERT_NE(city.terrain(), nullptr);
  // The default tiles: the city's 400 m box and 3 km a side, 400 m squares
  // at the root down to 50 m ones.
  const graph::TerrainLayout& l = city.terrain()->layout();
  EXPECT_EQ(l.grid, 17u);
  EXPECT_EQ(l.levels, 4u);
  EXPECT_NEAR(l.size, 6400.0, 1.0);
  EXPECT_GT(city.terrain()->record(0).error_m, 10.f);
  // Level ground everywhere: no tiles (the background draws it).
  stream::City level;
  ASSERT_EQ(level.open(bake("zero", [](double, double) { return 0.0; }), err), core::Status::Ok) << err;
  EXPECT_EQ(level.terrain(), nullptr);

  long allocations = -1;
  const Frame east = driveNorthStreet(hilly, 90.f, probe::ThreadMallocCounter::available() ? &allocations : nullptr);
  const Frame east_flat = driveNorthStreet(flat, 90.f), west = driveNorthStreet(hilly, 270.f);
  EXPECT_GT(east.stats.terrain_tiles, 0u);
  EXPECT_GE(east.stats.terrain_loads, east.stats.terrain_tiles);
  EXPECT_EQ(east.stats.terrain_load_errors, 0u);
  EXPECT_EQ(east_flat.stats.terrain_tiles, 0u);
  // Looking east the hill rises above the horizon; the flat package, and
  // the hilly one looking west (level ground), show sky there.
  const size_t hill_px = differingAboveTheHorizon(east, east_flat);
  EXPECT_GT(hill_px, 1000u) << "of the band's " << 320 * 43;
  EXPECT_LT(differingAboveTheHorizon(west, driveNorthStreet(flat, 270.f)), hill_px / 10);
  if (allocations >= 0) {
    EXPECT_EQ(allocations, 0) << "blvd's heap allocations on the render thread after warm-up";
  }

  // The tiles' slots and scratch are in the plan, and the stats add up to it.
  blvd_runtime_desc d{};
  d.struct_size = sizeof d;
  d.width = 320, d.height = 192;
  uint64_t cpu_hill = 0, gpu_hill = 0, cpu_flat = 0, gpu_flat = 0;
  d.package_path = hilly.c_str();
  ASSERT_EQ(blvd_memory_required(&d, nullptr, &cpu_hill, &gpu_hill), BLVD_OK) << blvd_last_error(nullptr);
  d.package_path = flat.c_str();
  ASSERT_EQ(blvd_memory_required(&d, nullptr, &cpu_flat, &gpu_flat), BLVD_OK) << blvd_last_error(nullptr);
  EXPECT_GT(east.stats.terrain_bytes, 0u);
  EXPECT_EQ(east.stats.staging.capacity_bytes + east.stats.table_bytes + east.stats.tracking_bytes +
                east.stats.terrain_bytes,
            cpu_hill);
  EXPECT_EQ(east.stats.gpu.capacity_bytes, gpu_hill);
  // 64 slots of a 17 x 17 tile and its skirts.
  EXPECT_GE(gpu_hill - gpu_flat, 64u * (17 * 17 + 4 * 17) * 36);
}

// The same package on a server (a real nginx), from a cold cache: the tiles
// a frame wants and the cache lacks are no load errors, the link prefetch
// fetches them, and the frames then show the hill as the local file does.
TEST(TerrainBake, TilesOverTheLinkAreFetchedAndDrawn) {
  const std::string hilly = bake("hill", hill);
  const std::string work = testDir() + "/served";
  std::filesystem::remove_all(work);
  std::filesystem::create_directories(work + "/www");
  std::filesystem::create_directories(work + "/nginx");
  std::filesystem::copy_file(hilly, work + "/www/hill.blvd");
  test::ServerProcess nginx;
  std::string why;
  ASSERT_TRUE(nginx.startNginx(work + "/nginx", work + "/www", 1 << 20, why)) << why;
  const std::string cache = work + "/cache";
  const Frame remote = driveNorthStreet(nginx.url("/hill.blvd"), 90.f, nullptr, cache.c_str());
  const Frame local = driveNorthStreet(hilly, 90.f);
  EXPECT_EQ(remote.stats.terrain_load_errors, 0u);
  EXPECT_GT(remote.stats.terrain_tiles, 0u);
  EXPECT_EQ(remote.stats.terrain_tiles, local.stats.terrain_tiles);
  EXPECT_GT(imaging::psnr(remote.px.data(), local.px.data(), remote.px.size() / 4), 40.0);
}

}  // namespace
}  // namespace blvd
