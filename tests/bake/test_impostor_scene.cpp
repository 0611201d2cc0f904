// Impostors on a synthetic city with known answers, baked and drawn end to
// end (OSM XML -> bake -> package -> runtime -> far metrics):
//   - a straight street looking at a tall block behind a low one: no spurious
//     pixel at a vantage point, and at the cell's start and end at most what
//     the depth mesh's contour tolerance allows (the bound is derived below);
//   - a hairpin whose last leg looks at a building behind the bend, in a
//     direction the cell's first leg never faces: drawn by its impostor at
//     every heading that shows it (its pixels above the horizon; a far
//     block's ground is a line there, measured by the route benchmark).
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "bake/bake.h"
#include "blvd/blvd.h"
#include "cli/far_metrics.h"
#include "common/osm_writer.h"
#include "stream/city.h"

namespace blvd {
namespace {

constexpr double kLat0 = 43.70, kLon0 = 7.40;  // where the synthetic city stands
constexpr uint32_t kW = 400, kH = 240;
constexpr double kDisplayFovY = 45.0;

// ---- The city, in metres east (x) and north (y) of (kLat0, kLon0).
using test::OsmWriter;

// A street grid (columns and rows below), every crossing a shared node so the
// bake makes junctions there, plus a hairpin from (0, 0) north and back to
// (80, 0) on the row y = 0, and three buildings.
const std::vector<double> kCols = {-200, -100, 250, 400, 550, 700, 850};
const std::vector<double> kRows = {-200, -100, 0, 200};

std::string sceneOsm() {
  OsmWriter w;
  // Grid nodes first, shared by the row and column ways.
  std::vector<std::vector<int>> id(kCols.size(), std::vector<int>(kRows.size()));
  for (size_t i = 0; i < kCols.size(); ++i)
    for (size_t j = 0; j < kRows.size(); ++j) id[i][j] = w.node(kCols[i], kRows[j]);
  // The hairpin's ends lie on the row y = 0 between x = -100 and x = 250.
  const int h0 = w.node(0, 0), h1 = w.node(80, 0);
  for (size_t j = 0; j < kRows.size(); ++j) {
    std::vector<int> row;
    for (size_t i = 0; i < kCols.size(); ++i) {
      row.push_back(id[i][j]);
      if (kRows[j] == 0 && kCols[i] == -100) row.push_back(h0), row.push_back(h1);
    }
    w.way(row, "    <tag k=\"highway\" v=\"residential\"/>\n");
  }
  for (size_t i = 0; i < kCols.size(); ++i) {
    std::vector<int> col;
    for (size_t j = 0; j < kRows.size(); ++j) col.push_back(id[i][j]);
    w.way(col, "    <tag k=\"highway\" v=\"residential\"/>\n");
  }
  // Hairpin: north to y = 120, a half circle of radius 40, south to (80, 0).
  std::vector<int> pin = {h0};
  pin.push_back(w.node(0, 60));
  pin.push_back(w.node(0, 120));
  for (int k = 1; k < 18; ++k) {
    const double a = M_PI - k * M_PI / 18;  // from west round to east, over the top
    pin.push_back(w.node(40 + 40 * std::cos(a), 120 + 40 * std::sin(a)));
  }
  pin.push_back(w.node(80, 120));
  pin.push_back(w.node(80, 60));
  pin.push_back(h1);
  w.way(pin, "    <tag k=\"highway\" v=\"residential\"/>\n");
  // Straight cell y = -200, x 250 -> 400, looking east: a low block ahead,
  // a tall one behind it, both in blocks that do not touch the cell.
  w.building(560, -185, 620, -150, 10);
  w.building(710, -185, 780, -135, 60);
  // Behind the hairpin's bend: south of the row y = -100, seen from its last leg.
  w.building(-60, -190, 20, -130, 40);
  return w.str();
}

// ---- The baked package, shared by the tests.
struct Scene {
  std::string package;
  bake::ImpostorBakeResult impostors;
  stream::City city;
};

Scene* scene() {
  static Scene* s = [] {
    auto* sc = new Scene;
    const std::string dir = std::string(BLVD_BINARY_DIR) + "/impostor_scene";
    ::mkdir(dir.c_str(), 0755);
    std::ofstream(dir + "/scene.osm") << sceneOsm();
    sc->package = dir + "/scene.blvd";
    bake::BakeOptions o;
    o.quiet = true;
    o.impostor.mode = bake::ImpostorMode::Both;
    o.impostor.display_width = kW;
    o.impostor.display_height = kH;
    o.on_impostors = [sc](const graph::StreetGraph&, const bake::ImpostorBakeResult& r, const bake::LodStats&) {
      sc->impostors = r;
    };
    bake::bakeCity(dir + "/scene.osm", sc->package, o);
    std::string err;
    EXPECT_EQ(sc->city.open(sc->package, err), core::Status::Ok) << err;
    return sc;
  }();
  return s;
}

glm::dvec2 local(const stream::City& city, double x, double y) {
  const geo::Enu e = city.frame().forward(kLat0 + y / 111320.0, kLon0 + x / (111320.0 * std::cos(kLat0 * M_PI / 180.0)));
  return {e.e, e.n};
}

// The cell from a to b (scene metres): its first and last points lie there.
uint32_t cellBetween(const stream::City& city, glm::dvec2 a, glm::dvec2 b) {
  const auto& g = city.graph();
  const glm::dvec2 A = local(city, a.x, a.y), B = local(city, b.x, b.y);
  for (uint32_t c = 0; c < g.cellCount(); ++c) {
    const auto& e = g.halfedges[c];
    if (glm::length(g.points[e.pts_begin] - A) < 1.0 && glm::length(g.points[e.pts_begin + e.pts_count - 1] - B) < 1.0)
      return c;
  }
  return graph::kNone;
}

// Poses along a cell every `step` metres: position and the heading of the
// segment it lies on.
struct Pose {
  glm::dvec2 p;
  double heading;
};
std::vector<Pose> along(const graph::StreetGraph& g, uint32_t cell, double step) {
  std::vector<Pose> out;
  const auto& e = g.halfedges[cell];
  double carry = 1.0;  // first pose 1 m in
  for (uint32_t i = 1; i < e.pts_count; ++i) {
    const glm::dvec2 a = g.points[e.pts_begin + i - 1], b = g.points[e.pts_begin + i];
    const double len = glm::length(b - a);
    double s = carry;
    for (; s < len; s += step)
      out.push_back({a + (b - a) * (s / len), std::atan2(b.x - a.x, b.y - a.y) * 180.0 / M_PI});
    carry = s - len;
  }
  return out;
}

class Frames {
 public:
  explicit Frames(const std::string& package) {
    blvd_runtime_desc d{};
    d.struct_size = sizeof d;
    d.package_path = package.c_str();
    d.width = kW;
    d.height = kH;
    d.fov_y_deg = float(kDisplayFovY);
    EXPECT_EQ(blvd_runtime_create(&d, &rt_), BLVD_OK) << blvd_last_error(nullptr);
  }
  ~Frames() { blvd_runtime_destroy(rt_); }
  // Pixels of block b above the horizon (its buildings, not its ground) in
  // the last full-model frame, and how many of them blvd drew with a layer
  // that stands for b.
  void buildingPixels(uint32_t b, size_t& full, size_t& drawn) const {
    full = drawn = 0;
    for (uint32_t y = 0; y + 1 < kH / 2; ++y)
      for (uint32_t x = 0; x < kW; ++x) {
        const size_t i = size_t(y) * kW + x;
        if (last_ref_ids_[i] != b + 1) continue;
        ++full;
        const uint32_t t = last_ids_[i];
        drawn += (t & cli::kItemImpostor) && last_holds_((t & ~cli::kItemImpostor) - 1, b);
      }
  }
  // The far metrics of blvd's layered impostors against the full model at a pose.
  cli::FarMetrics measure(const Scene& s, const Pose& pose, uint32_t& cell) {
    std::vector<uint8_t> ref(kW * kH * 4), img(ref.size());
    std::vector<uint32_t> ref_ids(kW * kH), ids(ref_ids.size());
    EXPECT_EQ(blvd_set_pose_local(rt_, pose.p.x, pose.p.y, float(pose.heading), 0.f), BLVD_OK);
    draw(BLVD_MODE_FULL, ref, ref_ids);
    cell = draw(BLVD_MODE_BLVD, img, ids);
    const auto& g = s.city.graph();
    const auto& layers = s.city.cellTables().impostors[cell].layered;
    cli::FarInputs in;
    in.w = kW, in.h = kH;
    in.ref_rgba = ref.data(), in.test_rgba = img.data(), in.ref_items = ref_ids.data(), in.test_items = ids.data();
    in.is_local = [&g, cell](uint32_t b) {
      return std::find(g.local_blocks.begin(cell), g.local_blocks.end(cell), b) != g.local_blocks.end(cell);
    };
    in.layer_holds = [&layers](uint32_t l, uint32_t b) {
      return l < layers.size() && std::binary_search(layers[l].blocks.begin(), layers[l].blocks.end(), b);
    };
    cli::FarMetrics fm = cli::measureFar(in);
    last_ref_ids_ = ref_ids;
    last_ids_ = ids;
    last_holds_ = in.layer_holds;
    return fm;
  }

 private:
  uint32_t draw(blvd_render_mode mode, std::vector<uint8_t>& px, std::vector<uint32_t>& ids) {
    EXPECT_EQ(blvd_set_render_mode(rt_, mode, 0.f), BLVD_OK);
    EXPECT_EQ(blvd_wait_resident(rt_, 60000), BLVD_OK) << blvd_last_error(rt_);
    blvd_frame_stats fs{};
    fs.struct_size = sizeof fs;
    EXPECT_EQ(blvd_render(rt_, &fs), BLVD_OK) << blvd_last_error(rt_);
    EXPECT_EQ(blvd_read_pixels(rt_, px.data(), px.size()), BLVD_OK);
    EXPECT_EQ(blvd_read_items(rt_, ids.data(), ids.size()), BLVD_OK);
    return fs.cell;
  }
  blvd_runtime* rt_ = nullptr;
  std::vector<uint32_t> last_ref_ids_, last_ids_;
  std::function<bool(uint32_t, uint32_t)> last_holds_;
};

// The block holding the building at scene point (x, y) of height >= min_top_m.
uint32_t blockWithBuilding(const stream::City& city, double x, double y, double min_top_m) {
  const glm::dvec2 p = local(city, x, y);
  const auto& blocks = city.blocks();
  for (uint32_t b = 0; b < blocks.size(); ++b) {
    const auto& r = blocks[b];  // glTF box: x east, y up, z south
    if (p.x >= r.bbox_min[0] && p.x <= r.bbox_max[0] && -p.y >= r.bbox_min[2] && -p.y <= r.bbox_max[2] &&
        r.bbox_max[1] >= min_top_m)
      return b;
  }
  return graph::kNone;
}

// Arc lengths along `cell` of its runs' vantage points (impostor_bake.cpp
// cellView: each run's middle), from the runs its layers serve.
std::vector<double> vantagePoints(const stream::City& city, uint32_t cell) {
  std::vector<double> from;
  for (const auto& l : city.cellTables().impostors[cell].layered) from.push_back(l.run_from_m);
  std::sort(from.begin(), from.end());
  from.erase(std::unique(from.begin(), from.end()), from.end());
  std::vector<double> out;
  const double len = city.graph().halfedges[cell].length;
  for (size_t k = 0; k < from.size(); ++k) out.push_back(0.5 * (from[k] + (k + 1 < from.size() ? from[k + 1] : len)));
  return out;
}

TEST(ImpostorScene, ATallBlockBehindALowOneHasNoRubberSheet) {
  Scene& s = *scene();
  const uint32_t cell = cellBetween(s.city, {250, -200}, {400, -200});
  ASSERT_NE(cell, graph::kNone);
  ASSERT_FALSE(s.city.cellTables().impostors[cell].layered.empty());
  double density = 1.0;
  for (const auto& r : s.impostors.records)
    if (r.cell == cell) density = std::min(density, r.density);
  const auto poses = along(s.city.graph(), cell, 1.0);  // pose i at arc 1 + i, scene x = 251 + i
  ASSERT_GT(poses.size(), 100u);
  const std::vector<double> vantage = vantagePoints(s.city, cell);
  ASSERT_GE(vantage.size(), 2u);  // 150 m: several runs
  Frames f(s.package);
  uint32_t at = 0;
  // At the first run's vantage point: no rubber sheet, no needle. The skirt
  // (one row hung under far geometry, depth_mesh.h) may show far ground that
  // the full model's rasteriser leaves sub-pixel at the horizon: the row
  // just below it, and nowhere else.
  const cli::FarMetrics there = f.measure(s, poses[size_t(std::lround(vantage.front())) - 1], at);
  ASSERT_EQ(at, cell);
  EXPECT_GT(there.far_px, 1000u);  // both buildings are in view
  size_t off_horizon = 0;
  for (size_t i = 0; i < there.classes.size(); ++i) off_horizon += there.classes[i] == 3 && i / kW != kH / 2;
  EXPECT_EQ(off_horizon, 0u);
  EXPECT_LE(there.spurious * kW * kH, double(kW));
  EXPECT_EQ(there.missing_objects, 0u);
  // At the cell's start and end, half a run from a vantage point. The depth
  // mesh's contour lies within its tolerance (1 texel) of the silhouette seen
  // from the vantage point; a texel spans 1/density display pixels there, and
  // from a viewer d metres from the buildings where the vantage point is
  // d_vantage away, the far geometry is magnified by d_vantage / d. Each
  // silhouette pixel is then off by at most m = (1 / density) * max(1,
  // d_vantage / d) + 1 (rasterisation); only what lies beyond the metric's
  // 2-px tolerance is spurious, so spurious <= max(0, m - 2) * (silhouette
  // pixels) / (frame pixels).
  for (const auto& [i, arc_vantage] : {std::pair{size_t(0), vantage.front()},
                                        std::pair{poses.size() - 1, vantage.back()}}) {
    const cli::FarMetrics m = f.measure(s, poses[i], at);
    ASSERT_EQ(at, cell);
    const double d_vantage = 560.0 - (250.0 + arc_vantage);
    const double d = 560.0 - (251.0 + double(i));
    const double px = (1.0 / density) * std::max(1.0, d_vantage / d) + 1.0;
    const double bound = std::max(0.0, px - 2.0) * double(m.silhouette_px) / (kW * kH);
    EXPECT_LE(m.spurious, bound) << "m " << px << " density " << density << " d " << d;
    EXPECT_EQ(m.missing_objects, 0u) << "d " << d;
  }
}

TEST(ImpostorScene, EachRunIsCapturedFromItsMiddle) {
  // The straight cell runs east along y = -200 from x = 250: the vantage
  // point of the run starting at arc s0 stands at x = 250 + its middle.
  Scene& s = *scene();
  const uint32_t cell = cellBetween(s.city, {250, -200}, {400, -200});
  ASSERT_NE(cell, graph::kNone);
  const std::vector<double> vantage = vantagePoints(s.city, cell);
  size_t checked = 0;
  for (const auto& r : s.impostors.records) {
    if (r.cell != cell) continue;
    const auto k = size_t(std::count_if(vantage.begin(), vantage.end(), [&](double v) { return v < r.run_from_m; }));
    ASSERT_LT(k, vantage.size());
    const glm::dvec2 want = local(s.city, 250.0 + vantage[k], -200.0);
    EXPECT_LT(glm::length(glm::dvec2(r.eye_enu.x, r.eye_enu.y) - want), 0.5)
        << "run from " << r.run_from_m << " m: eye at " << r.eye_enu.x << "," << r.eye_enu.y;
    ++checked;
  }
  EXPECT_GE(checked, vantage.size());
}

TEST(ImpostorScene, AHairpinShowsTheBlockBehindItsBendAtEveryHeading) {
  Scene& s = *scene();
  const uint32_t cell = cellBetween(s.city, {0, 0}, {80, 0});
  ASSERT_NE(cell, graph::kNone);
  const uint32_t behind = blockWithBuilding(s.city, -20, -160, 30);
  ASSERT_NE(behind, graph::kNone);
  const auto poses = along(s.city.graph(), cell, 10.0);
  ASSERT_GT(poses.size(), 25u);
  Frames f(s.package);
  size_t on_cell = 0, seen = 0;
  for (const Pose& p : poses) {
    uint32_t at = 0;
    const cli::FarMetrics m = f.measure(s, p, at);
    if (at != cell) continue;  // where the hairpin's legs meet the row, the row's cells
    ++on_cell;
    size_t full = 0, drawn = 0;
    f.buildingPixels(behind, full, drawn);
    if (full < 200) continue;
    ++seen;
    EXPECT_GE(drawn, 0.9 * full) << "pose at " << p.p.x << "," << p.p.y << " heading " << p.heading;
  }
  EXPECT_GT(on_cell, 20u);
  EXPECT_GT(seen, 3u);  // the block behind the bend is in view on the last leg, and only there
}

}  // namespace
}  // namespace blvd
