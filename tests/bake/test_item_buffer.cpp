// The bake's item buffer (CaptureRig::itemBuffer) on hand-made blocks: a far
// ground strip thinner than a pixel, which no pixel centre falls on, is
// counted by its outline; hidden behind a wall it is not; a block seen by its
// surfaces counts the same with outlines or without. And which edges are
// outlines (outlineLines).
#include <gtest/gtest.h>

#include <vector>

#include "bake/capture.h"

namespace blvd::bake {
namespace {

constexpr double kEye = 1.5;  // eye height, metres
constexpr int kRes = 128;     // the bake's item buffers: 128 x 128, 90°

// A flat ground rectangle, east [x0, x1] and north [n0, n1], facing up.
geo::MeshData groundQuad(double x0, double x1, double n0, double n1) {
  geo::MeshData m;
  const double pts[4][2] = {{x0, n0}, {x1, n0}, {x1, n1}, {x0, n1}};
  for (const auto& p : pts) m.positions.insert(m.positions.end(), {float(p[0]), 0.0f, float(-p[1])});
  m.indices = {0, 1, 2, 0, 2, 3};
  return m;
}

// A wall facing south (towards the eye), east [x0, x1], `north` metres ahead.
geo::MeshData wall(double x0, double x1, double north, double height) {
  geo::MeshData m;
  const double pts[4][2] = {{x0, 0}, {x1, 0}, {x1, height}, {x0, height}};
  for (const auto& p : pts) m.positions.insert(m.positions.end(), {float(p[0]), float(p[1]), float(-north)});
  m.indices = {0, 1, 2, 0, 2, 3};
  return m;
}

// Pixel counts of one view north from the origin at eye height: of the
// blocks' surfaces, and (with outlines) those plus the outline pixels of the
// blocks no surface pixel showed.
std::vector<uint32_t> countsNorth(const std::vector<geo::MeshData>& blocks, bool outlines) {
  CaptureRig rig(blocks, kRes, kRes);
  render::Camera cam;
  cam.eye_enu = {0.0, 0.0, kEye};
  cam.fov_y_deg = 90.0;
  cam.width = cam.height = kRes;
  cam.near_m = 0.3;
  cam.far_m = 2000.0;
  std::vector<uint32_t> counts(blocks.size(), 0u), lines(blocks.size(), 0u);
  rig.itemBuffer(cam, counts, outlines ? &lines : nullptr);
  for (size_t b = 0; b < blocks.size(); ++b) {
    if (counts[b]) {
      EXPECT_EQ(lines[b], 0u) << "block " << b << " has surface pixels and outline pixels";
    }
    counts[b] += lines[b];
  }
  return counts;
}

TEST(ItemBuffer, AFarGroundStripThinnerThanAPixelIsCountedByItsOutline) {
  // 400-430 m north, 290 m wide: 0.2° to 0.21° below the horizon, where the
  // first row's centre is 0.45° below it. What a display of 800 x 480 at 45°
  // shows on two rows.
  const std::vector<geo::MeshData> blocks = {groundQuad(-145, 145, 400, 430)};
  EXPECT_EQ(countsNorth(blocks, false)[0], 0u);
  const uint32_t px = countsNorth(blocks, true)[0];
  // Its columns: 290 m across at 400-430 m is 43-46 columns of a 90° view.
  EXPECT_GE(px, 40u) << "a pixel a column, across the strip";
  EXPECT_LE(px, 2u * 47u) << "its two long edges at most";
}

TEST(ItemBuffer, AStripBehindAWallIsNotCountedByItsOutline) {
  // The same strip behind a wall 100 m ahead, 20 m tall, wider than the view.
  const std::vector<geo::MeshData> blocks = {groundQuad(-145, 145, 400, 430), wall(-300, 300, 100, 20)};
  const std::vector<uint32_t> counts = countsNorth(blocks, true);
  EXPECT_EQ(counts[0], 0u);
  EXPECT_GT(counts[1], 0u);
}

TEST(ItemBuffer, ABlockItsSurfacesShowCountsTheSameWithOutlines) {
  // Ground 20-60 m ahead (rows of it), and the far strip beside it: the near
  // block's count is its pixels either way; the strip's outline shows too.
  const std::vector<geo::MeshData> blocks = {groundQuad(-30, 30, 20, 60), groundQuad(-145, 145, 400, 430)};
  const std::vector<uint32_t> plain = countsNorth(blocks, false), with = countsNorth(blocks, true);
  EXPECT_GT(plain[0], 100u);
  EXPECT_EQ(with[0], plain[0]);
  EXPECT_EQ(plain[1], 0u);
  EXPECT_GT(with[1], 0u);
}

TEST(ItemBuffer, OutlinesAreTheEdgesOfHorizontalFacesTheyDoNotShare) {
  // A ground quad: its four sides, not its diagonal.
  geo::MeshData lines = outlineLines(groundQuad(0, 10, 0, 10));
  EXPECT_EQ(lines.indices.size(), 8u);
  EXPECT_EQ(lines.vertexCount(), 4u);
  // A wall: no horizontal face, no outline.
  EXPECT_TRUE(outlineLines(wall(0, 10, 5, 3)).empty());
  // Both in one mesh: the quad's outline only, over the vertices it uses.
  geo::MeshData both = groundQuad(0, 10, 0, 10);
  both.append(wall(0, 10, 5, 3));
  lines = outlineLines(both);
  EXPECT_EQ(lines.indices.size(), 8u);
  EXPECT_EQ(lines.vertexCount(), 4u);
  for (size_t v = 0; v < lines.vertexCount(); ++v) EXPECT_EQ(lines.positions[v * 3 + 1], 0.0f);
  // The same mesh gives the same lines.
  EXPECT_EQ(outlineLines(both).indices, lines.indices);
}

}  // namespace
}  // namespace blvd::bake
