// Several views in one frame: a rear-view mirror is the scene behind
// flipped left-right, a stereo pair differs by its eye offset only, and views
// outside the frame are refused.
#include <gtest/gtest.h>

#include <vector>

#include "blvd/blvd.h"
#include "imaging/metrics.h"

namespace {

constexpr uint32_t kW = 320, kH = 192;
// The golden-view pose (tests/view): a street in Monaco.
constexpr double kLat = 43.735370, kLon = 7.417288;
constexpr float kHeading = 211.f;

struct Runtime {
  blvd_runtime* rt = nullptr;
  Runtime() {
    blvd_runtime_desc d{};
    d.struct_size = sizeof d;
    d.package_path = BLVD_TEST_PACKAGE;
    d.width = kW;
    d.height = kH;
    d.mode = BLVD_MODE_FULL;
    EXPECT_EQ(blvd_runtime_create(&d, &rt), BLVD_OK) << blvd_last_error(nullptr);
  }
  ~Runtime() { blvd_runtime_destroy(rt); }
  std::vector<uint8_t> pixels() {
    std::vector<uint8_t> px(kW * kH * 4);
    EXPECT_EQ(blvd_read_pixels(rt, px.data(), px.size()), BLVD_OK) << blvd_last_error(rt);
    return px;
  }
};

blvd_view view() {
  blvd_view v{};
  v.struct_size = sizeof v;
  return v;
}

std::vector<uint8_t> flipped(const std::vector<uint8_t>& px) {
  std::vector<uint8_t> out(px.size());
  for (uint32_t y = 0; y < kH; ++y)
    for (uint32_t x = 0; x < kW; ++x)
      for (int c = 0; c < 4; ++c) out[(y * kW + x) * 4 + c] = px[(y * kW + (kW - 1 - x)) * 4 + c];
  return out;
}

TEST(Views, RearMirrorIsTheSceneBehindFlipped) {
  Runtime r;
  ASSERT_NE(r.rt, nullptr);
  ASSERT_EQ(blvd_set_pose_geo(r.rt, kLat, kLon, kHeading + 180.f, 0.f), BLVD_OK);
  ASSERT_EQ(blvd_render(r.rt, nullptr), BLVD_OK) << blvd_last_error(r.rt);
  const std::vector<uint8_t> behind = r.pixels();

  ASSERT_EQ(blvd_set_pose_geo(r.rt, kLat, kLon, kHeading, 0.f), BLVD_OK);
  blvd_view mirror = view();
  mirror.yaw_offset_deg = 180.f;
  mirror.flags = BLVD_VIEW_MIRROR;
  blvd_frame_stats fs{};
  fs.struct_size = sizeof fs;
  ASSERT_EQ(blvd_render_views(r.rt, &mirror, 1, &fs), BLVD_OK) << blvd_last_error(r.rt);
  const std::vector<uint8_t> seen = r.pixels();
  const double same = blvd::imaging::psnr(seen.data(), flipped(behind).data(), seen.size() / 4);
  const double unflipped = blvd::imaging::psnr(seen.data(), behind.data(), seen.size() / 4);
  EXPECT_GE(same, 30.0);
  EXPECT_LT(unflipped, same - 5.0) << "the mirror view must actually be flipped";
  EXPECT_GT(fs.triangles, 0u);
}

TEST(Views, MainViewWithAMirrorInsetAndAStereoPair) {
  Runtime r;
  ASSERT_NE(r.rt, nullptr);
  ASSERT_EQ(blvd_set_pose_geo(r.rt, kLat, kLon, kHeading, 0.f), BLVD_OK);
  ASSERT_EQ(blvd_render(r.rt, nullptr), BLVD_OK);
  const std::vector<uint8_t> main_only = r.pixels();

  blvd_view views[2] = {view(), view()};
  views[1].x = kW / 4;
  views[1].y = 0;
  views[1].width = kW / 2;
  views[1].height = kH / 4;
  views[1].yaw_offset_deg = 180.f;
  views[1].flags = BLVD_VIEW_MIRROR;
  blvd_frame_stats fs{};
  fs.struct_size = sizeof fs;
  ASSERT_EQ(blvd_render_views(r.rt, views, 2, &fs), BLVD_OK) << blvd_last_error(r.rt);
  const std::vector<uint8_t> both = r.pixels();
  // Below the inset the frame is the main view; inside it, something else.
  size_t differ_inside = 0, differ_outside = 0;
  for (uint32_t y = 0; y < kH; ++y)
    for (uint32_t x = 0; x < kW; ++x) {
      const size_t i = (y * kW + x) * 4;
      const bool d = both[i] != main_only[i] || both[i + 1] != main_only[i + 1] || both[i + 2] != main_only[i + 2];
      const bool inside = x >= kW / 4 && x < kW / 4 + kW / 2 && y < kH / 4;
      (inside ? differ_inside : differ_outside) += d;
    }
  EXPECT_EQ(differ_outside, 0u);
  EXPECT_GT(differ_inside, size_t(kW / 2 * kH / 4) / 4);

  // Stereo: two half-width eyes 6.5 cm apart see nearly the same picture.
  blvd_view eyes[2] = {view(), view()};
  eyes[0].width = eyes[1].width = kW / 2;
  eyes[1].x = kW / 2;
  eyes[0].eye_offset_right_m = -0.0325f;
  eyes[1].eye_offset_right_m = 0.0325f;
  ASSERT_EQ(blvd_render_views(r.rt, eyes, 2, nullptr), BLVD_OK) << blvd_last_error(r.rt);
  const std::vector<uint8_t> pair = r.pixels();
  std::vector<uint8_t> left(kW / 2 * kH * 4), right(left.size());
  for (uint32_t y = 0; y < kH; ++y)
    for (uint32_t x = 0; x < kW / 2; ++x)
      for (int c = 0; c < 4; ++c) {
        left[(y * kW / 2 + x) * 4 + c] = pair[(y * kW + x) * 4 + c];
        right[(y * kW / 2 + x) * 4 + c] = pair[(y * kW + kW / 2 + x) * 4 + c];
      }
  const double ssim = blvd::imaging::ssim(left.data(), right.data(), kW / 2, kH);
  EXPECT_GT(ssim, 0.8);
  EXPECT_LT(ssim, 1.0) << "the eyes must be apart";
}

TEST(Views, ViewsOutsideTheFrameAreRefused) {
  Runtime r;
  ASSERT_NE(r.rt, nullptr);
  blvd_view v = view();
  v.x = kW - 10;
  v.width = 20;
  EXPECT_EQ(blvd_render_views(r.rt, &v, 1, nullptr), BLVD_ERR_INVALID_ARG);
  EXPECT_NE(std::string(blvd_last_error(r.rt)).find("outside"), std::string::npos);
  v = view();
  v.fov_y_deg = 200.f;
  EXPECT_EQ(blvd_render_views(r.rt, &v, 1, nullptr), BLVD_ERR_INVALID_ARG);
  EXPECT_EQ(blvd_render_views(r.rt, &v, 0, nullptr), BLVD_ERR_INVALID_ARG);
}

}  // namespace
