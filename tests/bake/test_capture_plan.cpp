// The capture plan (capture_plan.h) on hand-made blocks, drawn by the bake's
// capture rig: a far ground strip seen edge-on, thinner than a scout row,
// is found by its outline; ground the scout does see is planned without one.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "bake/capture.h"
#include "bake/capture_plan.h"
#include "bake/impostor_bake.h"
#include "track/track_test_util.h"

namespace blvd::bake {
namespace {

constexpr double kEye = 1.5;  // eye height, metres

// A flat ground rectangle, east [x0, x1] and north [n0, n1], facing up.
geo::MeshData groundQuad(double x0, double x1, double n0, double n1) {
  geo::MeshData m;
  const double pts[4][2] = {{x0, n0}, {x1, n0}, {x1, n1}, {x0, n1}};
  for (const auto& p : pts) {
    m.positions.insert(m.positions.end(), {float(p[0]), 0.0f, float(-p[1])});  // glTF: z = -north
    m.normals.insert(m.normals.end(), {0.0f, 1.0f, 0.0f});
    m.colors.insert(m.colors.end(), {120, 120, 110, 255});
  }
  m.indices = {0, 1, 2, 0, 2, 3};
  return m;
}

// The rectangle's outline every metre (ENU, on the ground).
std::vector<glm::dvec3> outline(double x0, double x1, double n0, double n1) {
  std::vector<glm::dvec3> out;
  for (double x = x0; x < x1; x += 1.0) out.emplace_back(x, n0, 0.0), out.emplace_back(x, n1, 0.0);
  for (double n = n0; n < n1; n += 1.0) out.emplace_back(x0, n, 0.0), out.emplace_back(x1, n, 0.0);
  return out;
}

// Does any shot hold the ground point (east, north)?
bool held(const std::vector<CaptureShot>& shots, double east, double north) {
  const glm::dvec3 p = render::enuToGltf({east, north, 0.0});
  for (const CaptureShot& s : shots) {
    const PinholeCamera pin = pinholeOf(s.cam);
    const glm::dvec3 v = p - pin.eye;
    const double z = glm::dot(v, pin.forward);
    if (z <= 0) continue;
    if (std::abs(glm::dot(v, pin.right) / z) <= s.tan_x && std::abs(glm::dot(v, pin.up) / z) <= s.tan_y) return true;
  }
  return false;
}

struct Plan {
  std::vector<geo::MeshData> meshes;
  BlockOutlines outlines;
  CapturePlanOptions opt;
  std::vector<CaptureShot> plan(bool with_outlines) {
    CaptureRig rig(meshes, 512, 512);
    std::vector<uint32_t> blocks;
    for (uint32_t b = 0; b < meshes.size(); ++b) blocks.push_back(b);
    return planCaptures(rig, {0.0, 0.0, kEye}, 0.0, -60.0, 60.0, blocks, opt, with_outlines ? &outlines : nullptr);
  }
};

// Is the strip's every part held, near and far edge, every 20 m across?
bool stripHeld(const std::vector<CaptureShot>& shots) {
  for (double x = -140; x <= 140; x += 20)
    if (!held(shots, x, 400.5) || !held(shots, x, 429.5)) return false;
  return true;
}

TEST(CapturePlan, AFarGroundStripThinnerThanAScoutRowIsPlannedByItsOutline) {
  // 400-430 m north, 40° wide: 0.016° tall from the eye, a scout row is
  // 0.45° there, so the scout sees it only where a row's centre happens to
  // cross it (a line of constant elevation bends across a planar view).
  Plan p;
  p.meshes = {groundQuad(-145, 145, 400, 430)};
  p.outlines = {outline(-145, 145, 400, 430)};
  p.opt.scout_min_px = 1000;  // this block counts as barely seen
  EXPECT_FALSE(stripHeld(p.plan(false)));
  const std::vector<CaptureShot> shots = p.plan(true);
  EXPECT_TRUE(stripHeld(shots));
  // Fitted to the strip: no shot reaches far above or below the horizon.
  for (const CaptureShot& s : shots) EXPECT_LT(std::atan(s.tan_y), 0.05) << "half-field " << s.tan_y;
}

TEST(CapturePlan, GroundTheScoutSeesNeedsNoOutline) {
  // 40-200 m north: several scout rows, planned by the scout alone; the
  // outline of a block seen on enough pixels adds nothing where the scout
  // found the block.
  Plan p;
  p.meshes = {groundQuad(-30, 30, 40, 200)};
  p.outlines = {outline(-30, 30, 40, 200)};
  p.opt.outline_gaps = false;
  const std::vector<CaptureShot> bare = p.plan(false), with = p.plan(true);
  ASSERT_FALSE(bare.empty());
  EXPECT_TRUE(held(bare, 0, 41) && held(bare, 0, 199) && held(bare, -25, 150) && held(bare, 25, 150));
  ASSERT_EQ(with.size(), bare.size());
  for (size_t i = 0; i < bare.size(); ++i) EXPECT_EQ(with[i].tan_x, bare[i].tan_x);
  // The scout leaves the near corners out (their last pixels fall outside
  // the fitted shots); the outline points in the azimuths it found empty
  // bring them in, and nothing taller.
  EXPECT_FALSE(held(bare, 29.5, 40.5));
  p.opt.outline_gaps = true;
  const std::vector<CaptureShot> gaps = p.plan(true);
  ASSERT_EQ(gaps.size(), bare.size());
  EXPECT_TRUE(held(gaps, 29.5, 40.5) && held(gaps, -29.5, 40.5));
  for (size_t i = 0; i < bare.size(); ++i) EXPECT_NEAR(gaps[i].tan_y, bare[i].tan_y, 0.1 * bare[i].tan_y);
}

// A mesh of both quads: one block.
geo::MeshData twoQuads(const geo::MeshData& a, const geo::MeshData& b) {
  geo::MeshData m = a;
  m.append(b);
  return m;
}

TEST(CapturePlan, AStripOfABlockTheScoutSeesElsewhereIsPlannedByItsOutline) {
  // One block: ground the scout sees well ahead, and a thin far strip 45-55°
  // to the right that falls between its rows. The block counts as seen, so
  // only the outline points in directions the scout found empty add rays.
  Plan p;
  p.meshes = {twoQuads(groundQuad(-30, 30, 40, 200), groundQuad(330, 420, 350, 358))};
  std::vector<glm::dvec3> o = outline(-30, 30, 40, 200), far = outline(330, 420, 350, 358);
  o.insert(o.end(), far.begin(), far.end());
  p.outlines = {o};
  auto farHeld = [](const std::vector<CaptureShot>& shots) {
    for (double x = 335; x <= 415; x += 20)
      if (!held(shots, x, 350.5) || !held(shots, x, 357.5)) return false;
    return true;
  };
  p.opt.outline_gaps = false;
  EXPECT_FALSE(farHeld(p.plan(true)));
  p.opt.outline_gaps = true;
  const std::vector<CaptureShot> shots = p.plan(true);
  EXPECT_TRUE(farHeld(shots));
  EXPECT_TRUE(held(shots, 0, 41) && held(shots, 0, 199));  // the seen ground stays planned
}

// The rows of shot `s` on the ground from north n0 to n1 straight ahead.
double rowsOn(const CaptureShot& s, double n0, double n1) {
  const double tall = std::atan(kEye / n0) - std::atan(kEye / n1);  // radians
  return tall / glm::radians(s.cam.fov_y_deg) * s.cam.height;
}

// The elevations, degrees, of a shot's bottom and top rows.
double bottomDeg(const CaptureShot& s) { return s.cam.pitch_deg - 0.5 * s.cam.fov_y_deg; }
double topDeg(const CaptureShot& s) { return s.cam.pitch_deg + 0.5 * s.cam.fov_y_deg; }

TEST(CapturePlan, AFarGroundStripKeepsItsRowsWhereTheTexelBudgetBites) {
  // 250-330 m north, 60 m wide: 0.08° tall from the eye. At the density a
  // cell's texel budget leaves (0.4), a capture has its least 16 rows: with
  // margin_deg above and below they spread over 3°, the strip under half a
  // row; with the thin margin above they spread over less, and the strip
  // gets more of them. Below, where the near ground drops as a viewer drives
  // on, the margin stays.
  Plan p;
  p.meshes = {groundQuad(-30, 30, 250, 330)};
  p.outlines = {outline(-30, 30, 250, 330)};
  p.opt.thin_margin_deg = 0;
  std::vector<CaptureShot> all_round = p.plan(true);
  p.opt.thin_margin_deg = 0.25;
  std::vector<CaptureShot> thin = p.plan(true);
  ASSERT_EQ(all_round.size(), 1u);
  ASSERT_EQ(thin.size(), 1u);
  for (CaptureShot* s : {&all_round[0], &thin[0]}) sizeCapture(*s, 0.4, p.opt);
  const CaptureShot &a = all_round[0], &t = thin[0];
  EXPECT_EQ(t.cam.height, 16);
  EXPECT_LT(rowsOn(a, 250, 330), 0.5);
  EXPECT_GT(rowsOn(t, 250, 330), 1.5 * rowsOn(a, 250, 330));
  EXPECT_NEAR(bottomDeg(t), bottomDeg(a), 0.05);
  EXPECT_LT(topDeg(t), topDeg(a) - 1.0);
  EXPECT_TRUE(held(thin, 0, 250.5) && held(thin, 0, 329.5) && held(thin, -29, 300) && held(thin, 29, 300));
  std::printf("strip rows: %.2f with the margin all round, %.2f with the thin margin above (%dx%d, %.2f deg tall)\n",
              rowsOn(a, 250, 330), rowsOn(t, 250, 330), t.cam.width, t.cam.height, t.cam.fov_y_deg);
}

// A capture of half-fields half_x by half_y degrees sized at density 1 with
// the layer atlas's gutter of 4 texels.
CaptureShot sizedWithGutter(double half_x_deg, double half_y_deg, CapturePlanOptions& opt) {
  opt.gutter_px = 4;
  CaptureShot s;
  s.tan_x = std::tan(glm::radians(half_x_deg));
  s.tan_y = std::tan(glm::radians(half_y_deg));
  sizeCapture(s, 1.0, opt);
  return s;
}

TEST(CapturePlan, AThinWideCaptureLeavesRoomForItsGutterInTheAtlas) {
  // 45° wide, 0.2° tall: 16 rows at least, so its width is capped, and the
  // cap leaves the atlas's gutter on both sides (a 512-wide capture never
  // packs into a 512 atlas with a gutter round it); the field grows to keep
  // both half-fields.
  CapturePlanOptions opt;
  const CaptureShot s = sizedWithGutter(22.5, 0.1, opt);
  EXPECT_EQ(s.cam.width, 504);
  EXPECT_EQ(s.cam.height, 16);
  EXPECT_GE(std::tan(glm::radians(0.5 * s.cam.fov_y_deg)), s.tan_x * 16 / 504 - 1e-9);
}

TEST(CapturePlan, ATallCaptureLeavesRoomForItsGutterToo) {
  // 20° wide, 70° tall: more display rows than the atlas holds, so the
  // density is cut until its height is the atlas's side less the gutter
  // (it would have packed at 512 only after the shrink loop cut both sides
  // by 15 %), and its width follows at the same density.
  CapturePlanOptions opt;
  const CaptureShot s = sizedWithGutter(10.0, 35.0, opt);
  EXPECT_EQ(s.cam.height, 504);
  EXPECT_NEAR(s.density, 504.0 / (2 * s.tan_y * opt.display_ppr), 1e-9);
  EXPECT_LT(s.cam.width, 504);
  EXPECT_NEAR(double(fullDensityTexels(s, opt)), 2 * s.tan_x * opt.display_ppr * s.density * 504, 1.0);
}

// The runs of a straight 80 m street (shorter than a run of 100 m, no turn): one on
// level ground; on a 10 % grade (8 m of climb) one per 3 m of it, three.
TEST(CellRuns, OnTerrainACellIsSplitWhereItClimbs) {
  blvd_test::GraphBuilder b;
  b.street(b.vertex(0, 0), b.vertex(80, 0));
  const graph::StreetGraph g = b.finish();
  const graph::HalfEdge& e = g.halfedges[0];
  ImpostorOptions opt;
  opt.run_length_m = 100;
  EXPECT_EQ(cellRuns(g, e, opt).size(), 1u);  // no terrain
  opt.ground = [](glm::dvec2 p) { return 50.0 + 0.1 * p.x; };
  EXPECT_NEAR(cellClimb(g, e, opt), 8.0, 1e-9);
  const auto runs = cellRuns(g, e, opt);
  ASSERT_EQ(runs.size(), 3u);
  EXPECT_DOUBLE_EQ(runs.front().first, 0.0);
  EXPECT_NEAR(runs[1].first, 80.0 / 3, 1e-4);  // the length is a float
  EXPECT_NEAR(runs.back().second, 80.0, 1e-4);
  opt.run_climb_m = 0;  // off
  EXPECT_EQ(cellRuns(g, e, opt).size(), 1u);
  opt.run_climb_m = 1, opt.max_runs = 4;  // 8 runs wanted, at most 4
  EXPECT_EQ(cellRuns(g, e, opt).size(), 4u);
  opt.run_climb_m = 3;
  opt.ground = [](glm::dvec2) { return 120.0; };  // level, high up
  EXPECT_EQ(cellRuns(g, e, opt).size(), 1u);
}

}  // namespace
}  // namespace blvd::bake
