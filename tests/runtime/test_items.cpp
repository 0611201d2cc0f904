// Object ids of a frame (blvd_read_items): blocks by id, impostor layers by
// BLVD_ITEM_IMPOSTOR, sky and ground 0; the ids are those of what the frame
// draws in each mode.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "blvd/blvd.h"
#include "stream/city.h"

namespace {

constexpr uint32_t kW = 320, kH = 192;

struct Items {
  blvd_runtime* rt = nullptr;
  Items() {
    blvd_runtime_desc d{};
    d.struct_size = sizeof d;
    d.package_path = BLVD_TEST_PACKAGE;
    d.width = kW;
    d.height = kH;
    EXPECT_EQ(blvd_runtime_create(&d, &rt), BLVD_OK) << blvd_last_error(nullptr);
  }
  ~Items() { blvd_runtime_destroy(rt); }
  std::vector<uint32_t> frame(blvd_render_mode mode, blvd_frame_stats& fs) {
    EXPECT_EQ(blvd_set_render_mode(rt, mode, 0.f), BLVD_OK);
    EXPECT_EQ(blvd_wait_resident(rt, 60000), BLVD_OK) << blvd_last_error(rt);
    fs = blvd_frame_stats{};
    fs.struct_size = sizeof fs;
    EXPECT_EQ(blvd_render(rt, &fs), BLVD_OK) << blvd_last_error(rt);
    std::vector<uint32_t> ids(kW * kH);
    EXPECT_EQ(blvd_read_items(rt, ids.data(), ids.size()), BLVD_OK) << blvd_last_error(rt);
    return ids;
  }
};

// A cell with layered impostors, and a pose 10 m along it.
bool impostorPose(const blvd::stream::City& city, uint32_t& cell, double& x, double& y, double& heading) {
  const auto& g = city.graph();
  const auto& imp = city.cellTables().impostors;
  for (uint32_t c = 0; c < imp.size(); ++c) {
    const auto& e = g.halfedges[c];
    if (imp[c].layered.size() < 2 || e.length < 40) continue;
    const glm::dvec2 a = g.points[e.pts_begin], b = g.points[e.pts_begin + 1];
    if (glm::length(b - a) < 20) continue;  // a pose 10 m along the first segment
    cell = c;
    const glm::dvec2 p = a + glm::normalize(b - a) * 10.0;
    x = p.x, y = p.y;
    heading = std::atan2(b.x - a.x, b.y - a.y) * 180.0 / 3.14159265358979;
    return true;
  }
  return false;
}

TEST(Items, EachModeShowsWhatItDraws) {
  blvd::stream::City city;
  std::string err;
  ASSERT_EQ(city.open(BLVD_TEST_PACKAGE, err), blvd::core::Status::Ok) << err;
  uint32_t cell = 0;
  double x = 0, y = 0, heading = 0;
  ASSERT_TRUE(impostorPose(city, cell, x, y, heading)) << "no straight impostor cell in the test package";
  Items r;
  ASSERT_NE(r.rt, nullptr);
  ASSERT_EQ(blvd_set_pose_local(r.rt, x, y, float(heading), 0.f), BLVD_OK);
  blvd_frame_stats fs{};
  const std::vector<uint32_t> local = r.frame(BLVD_MODE_LOCAL, fs);
  const auto& g = city.graph();
  const uint32_t* lb = g.local_blocks.begin(fs.cell);
  const uint32_t* le = g.local_blocks.end(fs.cell);
  size_t zero = 0;
  for (uint32_t id : local) {
    zero += id == 0;
    if (id) {
      EXPECT_NE(std::find(lb, le, id - 1), le) << "id " << id << " is not a local block of cell " << fs.cell;
    }
  }
  EXPECT_GT(zero, 0u);                // sky
  EXPECT_LT(zero, size_t(kW) * kH);  // and the street's blocks

  const std::vector<uint32_t> blvd = r.frame(BLVD_MODE_BLVD, fs);
  ASSERT_GE(fs.impostor_layers, 2u);
  uint32_t top = 0;
  size_t impostor_px = 0;
  for (uint32_t id : blvd)
    if (id & BLVD_ITEM_IMPOSTOR) ++impostor_px, top = std::max(top, id & ~BLVD_ITEM_IMPOSTOR);
  EXPECT_GT(impostor_px, 0u);
  EXPECT_GE(top, 1u);
  EXPECT_LE(top, city.cellTables().impostors[fs.cell].layered.size());  // the package's layer numbers

  const std::vector<uint32_t> full = r.frame(BLVD_MODE_FULL, fs);
  size_t far = 0;
  for (uint32_t id : full) {
    EXPECT_FALSE(id & BLVD_ITEM_IMPOSTOR);
    EXPECT_LE(id, city.blocks().size());
    far += id && std::find(lb, le, id - 1) == le;
  }
  EXPECT_GT(far, 0u);  // the full model shows far blocks where blvd shows impostors
}

TEST(Items, TheIdsReplaceTheFrameUntilTheNextRender) {
  Items r;
  ASSERT_NE(r.rt, nullptr);
  std::vector<uint32_t> ids(kW * kH);
  std::vector<uint8_t> px(kW * kH * 4);
  EXPECT_EQ(blvd_read_items(r.rt, ids.data(), ids.size()), BLVD_ERR_MISUSE);  // nothing rendered
  ASSERT_EQ(blvd_set_pose_geo(r.rt, 43.735370, 7.417288, 211.f, 0.f), BLVD_OK);
  ASSERT_EQ(blvd_render(r.rt, nullptr), BLVD_OK);
  EXPECT_EQ(blvd_read_items(r.rt, ids.data(), ids.size() - 1), BLVD_ERR_INVALID_ARG);
  EXPECT_NE(std::string(blvd_last_error(r.rt)).find("id buffer"), std::string::npos);
  EXPECT_EQ(blvd_read_items(r.rt, nullptr, ids.size()), BLVD_ERR_INVALID_ARG);
  EXPECT_EQ(blvd_read_items(r.rt, ids.data(), ids.size()), BLVD_OK);
  EXPECT_EQ(blvd_read_pixels(r.rt, px.data(), px.size()), BLVD_ERR_MISUSE);
  ASSERT_EQ(blvd_render(r.rt, nullptr), BLVD_OK);
  EXPECT_EQ(blvd_read_pixels(r.rt, px.data(), px.size()), BLVD_OK);
}

}  // namespace
