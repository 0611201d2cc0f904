// Blocks shared by neighbouring cells (blvd_runtime_desc.block_reuse): a new
// cell copies the local blocks another resident cell holds, GPU to GPU,
// instead of decoding them again. The copies must draw exactly what decoded
// blocks draw, the cell they come from must stay until they are done (with
// as few slots as the runtime allows and an upload budget that spreads each
// copy over many frames), and the stats must say how many were copied.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "blvd/blvd.h"
#include "drive.h"
#include "runtime_fixture.h"
#include "stream/city.h"

namespace {

using blvd_test::baseDesc;
using blvd_test::Runtime;
using blvd_test::statsOf;

blvd_test::Drive drive(uint32_t cells, double step_m) { return blvd_test::impostorDrive(cells, step_m); }

std::vector<uint8_t> frame(blvd_runtime* rt, const blvd_test::DrivePose& p, const blvd_runtime_desc& d) {
  return blvd_test::wholeFrame(rt, p.x, p.y, p.heading_deg, d.width, d.height, 30000);
}

// Draws every pose of `dr` in both runtimes and fails for each pair of frames
// that differ (the first three named); returns the number of differing frames.
uint32_t compareDrives(blvd_runtime* a, const blvd_runtime_desc& da, blvd_runtime* b, const blvd_runtime_desc& db,
                       const blvd_test::Drive& dr) {
  for (blvd_runtime* rt : {a, b})
    EXPECT_EQ(blvd_set_route(rt, dr.cells.data(), dr.cells.size()), BLVD_OK) << blvd_last_error(rt);
  uint32_t differing = 0;
  for (size_t i = 0; i < dr.poses.size(); ++i) {
    const std::vector<uint8_t> fa = frame(a, dr.poses[i], da), fb = frame(b, dr.poses[i], db);
    if (fa == fb) continue;
    size_t px = 0;
    for (size_t k = 0; k < fa.size(); k += 4) px += fa[k] != fb[k] || fa[k + 1] != fb[k + 1] || fa[k + 2] != fb[k + 2];
    if (differing++ < 3) ADD_FAILURE() << "pose " << i << " (cell " << dr.poses[i].cell << "): " << px << " pixels differ";
  }
  return differing;
}

// Small frames of the local blocks and the cell's impostors, with `slots` cell slots.
blvd_runtime_desc impostorDesc(uint32_t slots) {
  blvd_runtime_desc d = baseDesc();
  d.width = 160;
  d.height = 96;
  d.mode = BLVD_MODE_BLVD;
  d.max_resident_cells = slots;
  d.prefetch_priority = BLVD_PREFETCH_LOW;  // predictions run on a loaded CI machine too
  return d;
}

struct Case {
  uint32_t slots;
  float upload_budget_ms;
};

class BlockReuse : public ::testing::TestWithParam<Case> {};

TEST_P(BlockReuse, CopiedBlocksDrawWhatDecodedBlocksDraw) {
  const blvd_test::Drive dr = drive(24, 6.0);
  ASSERT_GE(dr.cells.size(), 10u);
  blvd_runtime_desc d = impostorDesc(GetParam().slots);
  d.upload_budget_ms = GetParam().upload_budget_ms;
  blvd_runtime_desc off = d;
  off.block_reuse = -1;
  Runtime a, b;
  ASSERT_EQ(blvd_runtime_create(&d, &a.rt), BLVD_OK) << blvd_last_error(nullptr);
  ASSERT_EQ(blvd_runtime_create(&off, &b.rt), BLVD_OK) << blvd_last_error(nullptr);
  EXPECT_EQ(compareDrives(a.rt, d, b.rt, off, dr), 0u) << "of " << dr.poses.size() << " frames";
  const blvd_stats with = statsOf(a.rt), without = statsOf(b.rt);
  EXPECT_EQ(with.load_errors, 0u) << blvd_last_error(a.rt);
  EXPECT_EQ(without.load_errors, 0u);
  // Neighbouring cells share blocks: most cells after the first copy some.
  EXPECT_GE(with.blocks_reused, with.loads / 2) << with.loads << " loads";
  EXPECT_GE(with.block_levels_copied, with.blocks_reused);
  EXPECT_EQ(without.blocks_reused, 0u);
  EXPECT_EQ(without.block_levels_copied, 0u);
  // The loader threads' CPU clocks (blvd_stats.loader_cpu_ms, prefetch_cpu_ms) ran while they decoded.
  EXPECT_GT(with.loader_cpu_ms + with.prefetch_cpu_ms, 0.0);
  EXPECT_GE(with.loader_cpu_ms, 0.0);
  EXPECT_GE(with.prefetch_cpu_ms, 0.0);
  EXPECT_LE(with.resident_cells, d.max_resident_cells ? d.max_resident_cells : 1000u);
  EXPECT_LE(with.gpu.high_water_bytes, with.gpu.capacity_bytes);
  RecordProperty("blocks_reused", std::to_string(with.blocks_reused));
  RecordProperty("loads", std::to_string(with.loads));
}

INSTANTIATE_TEST_SUITE_P(SlotsAndBudgets, BlockReuse,
                         ::testing::Values(Case{0, 0.f},       // the defaults
                                           Case{2, 0.f},       // the fewest slots: sources compete for them
                                           Case{3, 0.01f}),    // copies spread over many frames
                         [](const ::testing::TestParamInfo<Case>& i) {
                           return "slots" + std::to_string(i.param.slots) + (i.param.upload_budget_ms > 0 ? "_tinyUploads" : "");
                         });

// The frames of a pose do not depend on which cells came before it through
// the slots: a slot's textures keep the images of the cells it held earlier
// outside the current image's corner, and sampling must never reach them.
// Two runtimes with 4 and 3 slots load the same cells into other slots.
TEST(SlotHistory, ImpostorsDrawTheSameWhateverTheSlotsHeldBefore) {
  const blvd_test::Drive dr = drive(24, 6.0);
  ASSERT_GE(dr.cells.size(), 10u);
  const blvd_runtime_desc d = impostorDesc(4), three = impostorDesc(3);
  Runtime a, b;
  ASSERT_EQ(blvd_runtime_create(&d, &a.rt), BLVD_OK) << blvd_last_error(nullptr);
  ASSERT_EQ(blvd_runtime_create(&three, &b.rt), BLVD_OK) << blvd_last_error(nullptr);
  EXPECT_EQ(compareDrives(a.rt, d, b.rt, three, dr), 0u) << "of " << dr.poses.size() << " frames";
  EXPECT_GT(statsOf(a.rt).evictions + statsOf(b.rt).evictions, 0u) << "no slot was ever reused";
}

}  // namespace
