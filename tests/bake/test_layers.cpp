// D99 §4.1–4.2: extremal angles and layer assignment, against hand-computed
// values and brute-force sampling of M along [PQ].
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <glm/geometric.hpp>

#include "bake/layers.h"

using namespace blvd::bake;

namespace {
constexpr double kDeg = 3.14159265358979323846 / 180.0;

double bruteForce(glm::dvec2 P, glm::dvec2 Q, glm::dvec2 A, glm::dvec2 B) {
  double lo = 1e9, hi = -1e9;
  for (int i = 0; i <= 200000; ++i) {
    const glm::dvec2 M = P + (Q - P) * (i / 200000.0);
    const glm::dvec2 a = A - M, b = B - M;
    const double c = (a.x * b.x + a.y * b.y) / (std::hypot(a.x, a.y) * std::hypot(b.x, b.y));
    const double ang = std::acos(std::max(-1.0, std::min(1.0, c)));
    lo = std::min(lo, ang);
    hi = std::max(hi, ang);
  }
  return hi - lo;
}
}  // namespace

TEST(Layers, HandComputedAngleVariation) {
  // P=(-1,0), Q=(1,0), A=(0,1), B=(0,2): from M=(0,0) A and B line up (0°);
  // from P or Q the angle is atan(2) - atan(1) = 18.4349°. No interior extremum
  // of eq. 4/5 falls on [PQ] (x = ±√2).
  EXPECT_NEAR(angleVariation({-1, 0}, {1, 0}, {0, 1}, {0, 2}), (std::atan(2.0) - std::atan(1.0)), 1e-12);
  EXPECT_NEAR((std::atan(2.0) - std::atan(1.0)) / kDeg, 18.4349488, 1e-6);
  // AB ∥ PQ (y_B = 1): A=(0,1), B=(2,1) over P=(-3,0), Q=(3,0). The angle peaks
  // at H (x = 1, the median of AB): 2·atan(1) = 90°; its minimum is at P:
  // atan2 of (3,1) vs (5,1): atan(1/3) - atan(1/5).
  const double expect = 2 * std::atan(1.0) - (std::atan(1.0 / 3.0) - std::atan(1.0 / 5.0));
  EXPECT_NEAR(angleVariation({-3, 0}, {3, 0}, {0, 1}, {2, 1}), expect, 1e-12);
}

TEST(Layers, ClosedFormMatchesBruteForce) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> d(-50, 50);
  for (int i = 0; i < 300; ++i) {
    const glm::dvec2 P(d(rng), d(rng)), Q(d(rng), d(rng)), A(d(rng), d(rng)), B(d(rng), d(rng));
    // Skip points nearly on the line, where the angle jumps through π.
    const glm::dvec2 u = glm::normalize(Q - P);
    const auto off = [&](glm::dvec2 p) { return std::abs((p - P).x * -u.y + (p - P).y * u.x); };
    if (off(A) < 1 || off(B) < 1) continue;
    // The closed form finds the exact extrema; sampling can only fall short of them.
    const double exact = angleVariation(P, Q, A, B), sampled = bruteForce(P, Q, A, B);
    EXPECT_GE(exact, sampled - 1e-12) << "case " << i;
    EXPECT_NEAR(exact, sampled, 1e-4) << "case " << i;
  }
}

TEST(Layers, FarObjectsBehindEachOtherNeedLayersButSideBySideDoNot) {
  // A 40 m street along x. Two blocks far ahead, one behind the other: strong
  // parallax. Two blocks side by side at the same distance, far off to one
  // side: they never overlap in image space (critical zones), weight 0.
  const glm::dvec2 P(0, 0), Q(40, 0);
  auto box = [](double x, double y, double s) {
    return LayerObject{0, convexHull({{x, y}, {x + s, y}, {x + s, y + s}, {x, y + s}}), 1.0};
  };
  std::vector<LayerObject> objs = {box(100, -10, 20), box(300, -10, 20), box(60, 200, 20), box(200, 200, 20)};
  const double T = 0.01;
  const auto w01 = objectWeight(P, Q, objs[0], objs[1]);
  EXPECT_GT(w01, T);
  EXPECT_EQ(objectWeight(P, Q, objs[2], objs[3]), 0.0);
  const LayerAssignment la = assignLayers(P, Q, objs, T);
  ASSERT_GE(la.layers.size(), 2u);
  // 0 and 1 are in different layers.
  for (const auto& layer : la.layers) {
    const bool has0 = std::find(layer.begin(), layer.end(), 0u) != layer.end();
    const bool has1 = std::find(layer.begin(), layer.end(), 1u) != layer.end();
    EXPECT_FALSE(has0 && has1);
  }
  // Every object is in exactly one layer, and no layer holds a pair above T.
  std::vector<int> seen(objs.size(), 0);
  for (const auto& layer : la.layers)
    for (uint32_t i : layer) {
      ++seen[i];
      for (uint32_t j : layer) EXPECT_LE(la.weights[i * objs.size() + j], T);
    }
  for (int s : seen) EXPECT_EQ(s, 1);
}

TEST(Layers, LandmarkWeightRaisesLayerCount) {
  const glm::dvec2 P(0, 0), Q(10, 0);
  auto box = [](double x, double s, double scale) {
    return LayerObject{0, convexHull({{x, -s}, {x + s, -s}, {x + s, s}, {x, s}}), scale};
  };
  std::vector<LayerObject> objs = {box(500, 10, 1), box(520, 10, 1)};
  const double w = objectWeight(P, Q, objs[0], objs[1]);
  ASSERT_GT(w, 0.0);
  EXPECT_EQ(assignLayers(P, Q, objs, w * 1.5).layers.size(), 1u);
  objs[1].weight_scale = 3.0;
  EXPECT_EQ(assignLayers(P, Q, objs, w * 1.5).layers.size(), 2u);
}

TEST(Layers, PixelThreshold) {
  // 10 px at 800 px across 69.39° (45° vertical at 800x480).
  EXPECT_NEAR(pixelsToRadians(10, 800, 69.3903) / kDeg, 0.8674, 1e-3);
}

TEST(Layers, CapMergesTheCheapestLayers) {
  // Five objects in a row far down the street: every pair conflicts, so D99
  // gives five layers; capping at 2 keeps every object exactly once.
  const glm::dvec2 P(0, 0), Q(50, 0);
  std::vector<LayerObject> objs;
  for (int i = 0; i < 5; ++i) {
    const double x = 100 + 60 * i;
    objs.push_back({0, convexHull({{x, -5}, {x + 10, -5}, {x + 10, 5}, {x, 5}}), 1.0});
  }
  LayerAssignment la = assignLayers(P, Q, objs, 1e-4);
  ASSERT_EQ(la.layers.size(), 5u);
  const double worst = capLayers(la, objs.size(), 2);
  EXPECT_EQ(la.layers.size(), 2u);
  EXPECT_GT(worst, 1e-4);
  std::vector<int> seen(objs.size(), 0);
  for (const auto& l : la.layers)
    for (uint32_t i : l) ++seen[i];
  for (int s : seen) EXPECT_EQ(s, 1);
  EXPECT_EQ(capLayers(la, objs.size(), 2), 0.0);  // already within the cap
}

TEST(Layers, CapMovesEachObjectOfTheDroppedLayerOnItsOwn) {
  // Layers {0} {1} {2,3}; object 2 conflicts with 0, object 3 with 1. Merging
  // the last layer whole puts a heavy pair together whichever layer takes it;
  // object by object, 2 joins 1 and 3 joins 0, and the worst admitted weight
  // is the light one.
  LayerAssignment la;
  la.layers = {{0}, {1}, {2, 3}};
  const size_t n = 4;
  la.weights.assign(n * n, 0.0);
  auto w = [&](uint32_t i, uint32_t j, double v) { la.weights[i * n + j] = la.weights[j * n + i] = v; };
  w(0, 1, 0.5);
  w(2, 0, 0.9);
  w(2, 1, 0.01);
  w(3, 0, 0.02);
  w(3, 1, 0.8);
  const double worst = capLayers(la, n, 2);
  ASSERT_EQ(la.layers.size(), 2u);
  EXPECT_DOUBLE_EQ(worst, 0.02);
  EXPECT_EQ(la.layers[0], (std::vector<uint32_t>{0, 3}));
  EXPECT_EQ(la.layers[1], (std::vector<uint32_t>{1, 2}));
}
