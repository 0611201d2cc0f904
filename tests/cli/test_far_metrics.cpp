// The far-city metrics (sdk/cli/far_metrics.h) on hand-made image pairs with
// known answers: a shifted silhouette, a hole, a needle, a missing object.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "cli/far_metrics.h"

namespace blvd::cli {
namespace {

constexpr int W = 160, H = 120;
constexpr uint32_t kLocal = 7, kFarA = 20, kFarB = 21;

// A frame pair with ids; colours follow the ids (sky blue, block colours).
struct Pair {
  std::vector<uint8_t> ref = std::vector<uint8_t>(W * H * 4), test = ref;
  std::vector<uint32_t> ref_ids = std::vector<uint32_t>(W * H, 0), test_ids = ref_ids;

  static void colour(uint32_t id, uint8_t* p) {
    p[0] = uint8_t(id ? 40 + 9 * (id & 15) : 120);
    p[1] = uint8_t(id ? 60 : 170);
    p[2] = uint8_t(id ? 30 : 230);
    p[3] = 255;
  }
  void paint(bool ref_side, int x0, int y0, int x1, int y1, uint32_t id, uint32_t colour_id) {
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) {
        const size_t i = size_t(y) * W + x;
        (ref_side ? ref_ids : test_ids)[i] = id;
        colour(colour_id, &(ref_side ? ref : test)[i * 4]);
      }
  }
  // The same block in both: the reference as geometry, the test as layer `layer`.
  void both(int x0, int y0, int x1, int y1, uint32_t block, int layer) {
    paint(true, x0, y0, x1, y1, block + 1, block + 1);
    paint(false, x0, y0, x1, y1, layer < 0 ? block + 1 : (kItemImpostor | uint32_t(layer + 1)), block + 1);
  }
  Pair() {
    paint(true, 0, 0, W, H, 0, 0);
    paint(false, 0, 0, W, H, 0, 0);
  }
  FarMetrics measure() const {
    FarInputs in;
    in.w = W, in.h = H;
    in.ref_rgba = ref.data(), in.test_rgba = test.data();
    in.ref_items = ref_ids.data(), in.test_items = test_ids.data();
    in.is_local = [](uint32_t b) { return b == kLocal; };
    in.layer_holds = [](uint32_t layer, uint32_t b) { return (layer == 0 && b == kFarA) || (layer == 1 && b == kFarB); };
    return measureFar(in);
  }
};

TEST(FarMetrics, IdenticalFramesHaveNoError) {
  Pair p;
  p.both(10, 10, 60, 50, kFarA, 0);
  p.both(80, 20, 120, 90, kFarB, 1);
  p.both(0, 90, 160, 120, kLocal, -1);  // local geometry is not far
  const FarMetrics m = p.measure();
  EXPECT_EQ(m.far_px, 50u * 40 + 40 * 70);
  EXPECT_EQ(m.far_bad, 0.0);
  EXPECT_EQ(m.holes, 0.0);
  EXPECT_EQ(m.spurious, 0.0);
  EXPECT_EQ(m.missing_objects, 0u);
  EXPECT_EQ(m.visibility_error_px, 0.0);
}

TEST(FarMetrics, AShiftedSilhouetteIsMeasuredInPixels) {
  // A far block spanning the frame's height, drawn 5 px to the right: its two
  // silhouettes (left and right edges; the border is none) move by 5 px.
  Pair p;
  p.paint(true, 40, 0, 90, H, kFarA + 1, kFarA + 1);
  p.paint(false, 45, 0, 95, H, kItemImpostor | 1u, kFarA + 1);
  const FarMetrics m = p.measure();
  EXPECT_NEAR(m.visibility_error_px, 5.0, 1e-6);
  EXPECT_NEAR(m.silhouette_distance_px, 5.0, 1e-6);
  // 5 columns of the far block now show sky: holes, and wrong colour.
  EXPECT_NEAR(m.holes, 5.0 * H / (W * H), 1e-9);
  EXPECT_NEAR(m.far_bad, 5.0 / 50.0, 1e-9);
  // The 5 columns drawn past it are spurious, except the 2 px next to it.
  EXPECT_NEAR(m.spurious, 3.0 * H / (W * H), 1e-9);
}

TEST(FarMetrics, AHoleIsAShareOfTheFrame) {
  Pair p;
  p.both(20, 20, 100, 100, kFarA, 0);
  p.paint(false, 40, 40, 60, 60, 0, 0);  // sky shows through a 20 x 20 hole
  const FarMetrics m = p.measure();
  EXPECT_NEAR(m.holes, 400.0 / (W * H), 1e-12);
  EXPECT_NEAR(m.far_bad, 400.0 / (80.0 * 80.0), 1e-12);
  EXPECT_EQ(m.spurious, 0.0);
  // The hole's rim is a silhouette only in the test, around 20 x 20 pixels
  // of wrong visibility: 20 px of error, and 20 px from the nearest outer
  // silhouette at its centre; the p95 of all silhouette pixels sees both.
  EXPECT_NEAR(m.visibility_error_px, 20.0, 1e-6);
  EXPECT_GT(m.silhouette_distance_px, 10.0);
}

TEST(FarMetrics, ACrackBetweenLayersMeasuresItsWidth) {
  // Two far blocks side by side, the test's layers 6 px apart where they
  // meet: sky through a crack 6 px wide and 80 px tall, far inside F. The
  // error is the crack's width; the silhouette distance, its distance from
  // F's outline (up to 40 px at its middle).
  Pair p;
  p.both(20, 20, 80, 100, kFarA, 0);
  p.both(80, 20, 140, 100, kFarB, 1);
  p.paint(false, 77, 20, 83, 100, 0, 0);
  const FarMetrics m = p.measure();
  EXPECT_NEAR(m.visibility_error_px, 6.0, 1e-6);
  EXPECT_GT(m.silhouette_distance_px, 20.0);
  EXPECT_NEAR(m.holes, 6.0 * 80 / (W * H), 1e-12);
  // A block not drawn at all: its smaller extent (30 px).
  Pair q;
  q.both(20, 20, 80, 100, kFarA, 0);
  q.paint(true, 100, 40, 150, 70, kFarB + 1, kFarB + 1);
  EXPECT_NEAR(q.measure().visibility_error_px, 30.0, 1e-6);
}

TEST(FarMetrics, ANeedleIntoTheSkyIsSpurious) {
  Pair p;
  p.both(20, 80, 140, 120, kFarA, 0);
  // A 1-px needle from the far block's top up 50 px, in the block's colour.
  p.paint(false, 70, 30, 71, 80, kItemImpostor | 1u, kFarA + 1);
  const FarMetrics m = p.measure();
  EXPECT_NEAR(m.spurious, 48.0 / (W * H), 1e-12);  // its 2 px next to the block are tolerated
  EXPECT_EQ(m.holes, 0.0);
  EXPECT_EQ(m.far_bad, 0.0);
  // A needle of the sky's colour is not wrong: nothing to see.
  Pair q;
  q.both(20, 80, 140, 120, kFarA, 0);
  q.paint(false, 70, 30, 71, 80, kItemImpostor | 1u, 0);
  EXPECT_EQ(q.measure().spurious, 0.0);
}

TEST(FarMetrics, AnObjectShownByTheWrongLayerIsMissing) {
  // Block A (300 px) is covered by layer 1, which stands for B, on 2/3 of it.
  Pair p;
  p.both(10, 10, 40, 20, kFarA, 0);
  p.paint(false, 10, 10, 30, 20, kItemImpostor | 2u, kFarB + 1);
  FarMetrics m = p.measure();
  ASSERT_EQ(m.missing_objects, 1u);
  EXPECT_EQ(m.missing[0], kFarA);
  // What shows on its pixels says why: the wrong layer on 200, itself on 100.
  ASSERT_EQ(m.missing_shown.size(), 1u);
  EXPECT_EQ(m.missing_shown[0].block, kFarA);
  EXPECT_EQ(m.missing_shown[0].px, 300u);
  EXPECT_EQ(m.missing_shown[0].other_layer, 200u);
  EXPECT_EQ(m.missing_shown[0].own, 100u);
  EXPECT_EQ(m.missing_shown[0].geometry + m.missing_shown[0].nothing, 0u);
  // Covered by its own layer on exactly half: not missing.
  Pair q;
  q.both(10, 10, 40, 20, kFarA, 0);
  q.paint(false, 10, 10, 25, 20, kItemImpostor | 2u, kFarB + 1);
  EXPECT_EQ(q.measure().missing_objects, 0u);
  // Smaller than 200 px: never counted.
  Pair r;
  r.both(10, 10, 29, 20, kFarA, 0);
  r.paint(false, 10, 10, 29, 20, 0, 0);
  EXPECT_EQ(r.measure().missing_objects, 0u);
  // Not drawn at all: its pixels show nothing.
  Pair z;
  z.both(10, 10, 40, 20, kFarA, 0);
  z.paint(false, 10, 10, 40, 20, 0, 0);
  const FarMetrics mz = z.measure();
  ASSERT_EQ(mz.missing_shown.size(), 1u);
  EXPECT_EQ(mz.missing_shown[0].nothing, 300u);
}

TEST(FarMetrics, DistanceTransformIsExact) {
  std::mt19937 rng(3);
  const int w = 37, h = 23;
  std::vector<uint8_t> seed(size_t(w) * h, 0);
  for (int k = 0; k < 12; ++k) seed[rng() % seed.size()] = 1;
  const std::vector<float> d = distanceTransform2(seed, w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double best = INFINITY;
      for (int v = 0; v < h; ++v)
        for (int u = 0; u < w; ++u)
          if (seed[size_t(v) * w + u]) best = std::min(best, double((u - x) * (u - x) + (v - y) * (v - y)));
      ASSERT_EQ(d[size_t(y) * w + x], float(best)) << x << "," << y;
    }
  EXPECT_TRUE(std::isinf(distanceTransform2(std::vector<uint8_t>(6, 0), 3, 2)[0]));
}

}  // namespace
}  // namespace blvd::cli
