// A sim_feed Monaco drive (NMEA + candump + truth, written by the sample in the
// CTest fixture sim_feed_trace) replayed through the public C API as a host
// would: NMEA bytes -> gnss adapter -> blvd_feed_gnss, candump lines ->
// blvd_can_frame -> blvd_feed_can_frame with a Toyota profile; blvd_get_pose at
// every truth epoch. The matched cells must follow the truth's route.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "blvd/blvd.h"
#include "common/test_runtime.h"
#include "trace_inputs.h"

namespace {

using namespace blvd::trace_test;

TEST(TraceReplay, SimFeedMonacoCellsFollowTruth) {
  const std::vector<Truth> truth = readTruth(BLVD_SIM_TRACE ".csv");
  ASSERT_GT(truth.size(), 120u);
  const std::vector<Input> inputs = readInputs(BLVD_SIM_TRACE ".nmea", BLVD_SIM_TRACE ".log");
  size_t fixes = 0, frames = 0;
  for (const Input& i : inputs) (i.gnss ? fixes : frames)++;
  EXPECT_EQ(fixes, truth.size());  // one per epoch (lost ones as "no fix")
  EXPECT_GT(frames, 50 * truth.size());

  blvd_runtime* rt = blvd::test::createTrackingRuntime();
  ASSERT_NE(rt, nullptr);
  blvd_can_profile* prof = createToyotaProfile();
  ASSERT_NE(prof, nullptr);

  // The route, in order, from the truth (each cell once).
  std::vector<uint32_t> route;
  for (const Truth& t : truth)
    if (route.empty() || route.back() != t.cell) route.push_back(t.cell);
  std::map<uint32_t, size_t> index;
  for (size_t i = 0; i < route.size(); ++i) index.emplace(route[i], i);

  const double t0 = truth.front().t, warmup_s = 10;
  size_t k = 0, epochs = 0, on_cell = 0, off_route = 0, backwards = 0;
  size_t last_index = 0;
  std::vector<uint32_t> matched;  // run-length sequence of matched cells after the warm-up
  for (const Truth& tr : truth) {
    for (; k < inputs.size() && inputs[k].t <= tr.t + 1e-6; ++k) {
      ASSERT_EQ(feed(rt, prof, inputs[k]), BLVD_OK) << "input " << k;
    }
    blvd_pose p{};
    p.struct_size = sizeof p;
    ASSERT_EQ(blvd_get_pose(rt, tr.t, &p), BLVD_OK) << blvd_last_error(rt);
    if (tr.t - t0 < warmup_s) continue;
    ASSERT_TRUE(p.flags & BLVD_POSE_MATCHED) << "t=" << tr.t - t0;
    // The camera for rendering sits on the matched street, near the fused
    // position, at eye height, looking along the street.
    EXPECT_LT(std::hypot(p.camera_x - p.x, p.camera_y - p.y), 10.0) << "t=" << tr.t - t0;
    EXPECT_NEAR(p.camera_z, 1.5, 0.5);
    EXPECT_LT(std::fabs(std::remainder(p.camera_heading_deg - p.heading_deg, 360.0)), 60.0) << "t=" << tr.t - t0;
    ++epochs;
    on_cell += p.cell == tr.cell;
    if (!matched.empty() && matched.back() == p.cell) continue;
    matched.push_back(p.cell);
    const auto it = index.find(p.cell);
    if (it == index.end()) {
      ++off_route;
      continue;
    }
    if (it->second < last_index) ++backwards;
    last_index = std::max(last_index, it->second);
  }
  blvd_can_profile_destroy(prof);
  blvd_runtime_destroy(rt);

  // The matched sequence follows the route: a cell off the route or a step back
  // is a wrong match that lasted at least one epoch. Allow a few (junctions at
  // sigma 5 m), never many.
  const double share = static_cast<double>(on_cell) / static_cast<double>(epochs);
  EXPECT_GE(share, 0.95) << on_cell << " of " << epochs << " epochs on the true cell";
  EXPECT_LE(off_route, 3u) << "matched cells not on the route";
  EXPECT_LE(backwards, 2u) << "steps back along the route";
  // Every route cell after the warm-up was matched at some epoch, but for short
  // ones crossed between two epochs.
  size_t seen = 0;
  for (uint32_t c : matched) seen += index.count(c);
  EXPECT_GE(seen + 8, route.size() - route.size() / 10) << "matched " << seen << " of " << route.size() << " route cells";
}

}  // namespace
