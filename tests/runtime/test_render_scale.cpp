// The frame budget's second knob through the C API (decision 0008):
// with min_render_scale < 1 a target the coarsest levels cannot meet makes
// blvd draw fewer pixels and stretch them; the frame read back is still the
// full frame and close to the unscaled one; bad scales are refused; without
// min_render_scale nothing is ever scaled.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "blvd/blvd.h"
#include "imaging/metrics.h"
#include "runtime_fixture.h"

namespace {

using blvd_test::baseDesc;
using blvd_test::Runtime;
using blvd_test::statsOf;

// The golden-view pose (tests/view): a street in Monaco.
constexpr double kLat = 43.735370, kLon = 7.417288;
constexpr float kHeading = 211.f;

std::vector<uint8_t> frame(blvd_runtime* rt, const blvd_runtime_desc& d) {
  std::vector<uint8_t> px(size_t(d.width) * d.height * 4);
  EXPECT_EQ(blvd_read_pixels(rt, px.data(), px.size()), BLVD_OK) << blvd_last_error(rt);
  return px;
}

// Renders `frames` frames at the pose; the last one's stats.
blvd_stats drive(blvd_runtime* rt, int frames) {
  EXPECT_EQ(blvd_set_pose_geo(rt, kLat, kLon, kHeading, 0.f), BLVD_OK);
  EXPECT_EQ(blvd_wait_resident(rt, 30000), BLVD_OK) << blvd_last_error(rt);
  for (int i = 0; i < frames; ++i) EXPECT_EQ(blvd_render(rt, nullptr), BLVD_OK) << blvd_last_error(rt);
  return statsOf(rt);
}

TEST(RenderScale, AnUnreachableTargetScalesDownToTheMinimum) {
  blvd_runtime_desc d = baseDesc();
  Runtime full;
  ASSERT_EQ(blvd_runtime_create(&d, &full.rt), BLVD_OK) << blvd_last_error(nullptr);
  const blvd_stats f = drive(full.rt, 2);
  EXPECT_EQ(f.render_scale, 1.f);
  EXPECT_EQ(f.frame_aim_ms, 0.f);  // no target, no aim
  const std::vector<uint8_t> reference = frame(full.rt, d);

  d.target_frame_ms = 0.01f;  // no frame meets it
  d.min_render_scale = 0.5f;
  Runtime scaled;
  ASSERT_EQ(blvd_runtime_create(&d, &scaled.rt), BLVD_OK) << blvd_last_error(nullptr);
  // Polygons first: the budget halves a frame down to the coarsest levels,
  // then the scale steps by 1/16 down to 0.5.
  const blvd_stats s = drive(scaled.rt, 60);
  EXPECT_EQ(s.render_scale, 0.5f);
  EXPECT_EQ(s.budget_unreachable, 1u);
  // Every frame misses by far: the aim sits at its lowest, 0.92 × the target.
  EXPECT_NEAR(s.frame_aim_ms, 0.92f * 0.01f, 1e-5f);
  const std::vector<uint8_t> half = frame(scaled.rt, d);
  // The whole frame was written (stretched), and it is the same street.
  const blvd::imaging::ImageMetrics m =
      blvd::imaging::compareImages(reference.data(), half.data(), int(d.width), int(d.height));
  RecordProperty("ssim", std::to_string(m.ssim));
  EXPECT_GT(m.ssim, 0.7) << "scaled frame is not the same view";
  EXPECT_LT(m.ssim, 0.999) << "a frame drawn at half the pixels cannot be identical";
}

TEST(RenderScale, WithoutMinRenderScaleNothingIsScaled) {
  blvd_runtime_desc d = baseDesc();
  d.target_frame_ms = 0.01f;
  Runtime r;
  ASSERT_EQ(blvd_runtime_create(&d, &r.rt), BLVD_OK) << blvd_last_error(nullptr);
  const blvd_stats s = drive(r.rt, 30);
  EXPECT_EQ(s.render_scale, 1.f);
  EXPECT_EQ(s.budget_unreachable, 1u);
}

TEST(RenderScale, OutOfRangeScalesAreRefused) {
  for (float bad : {0.1f, 1.5f, -1.f}) {
    blvd_runtime_desc d = baseDesc();
    d.target_frame_ms = 5.f;
    d.min_render_scale = bad;
    blvd_runtime* rt = nullptr;
    EXPECT_EQ(blvd_runtime_create(&d, &rt), BLVD_ERR_INVALID_ARG) << bad;
    EXPECT_EQ(rt, nullptr);
    EXPECT_NE(std::string(blvd_last_error(nullptr)).find("min_render_scale"), std::string::npos);
  }
}

}  // namespace
