// Every allocation of a cell's load failing in turn. The cell decodes on a
// host executor whose jobs this test runs on its own thread, so a failer can
// cover exactly one load: NewFailer (tests/fault) fails each C++ allocation
// of blvd's (this runs under ASan + LeakSanitizer in CI's sanitizer stage),
// ThreadMallocFailer (sdk/cli/malloc_probe.h) each malloc-family call of the
// C libraries (stb_image, libwebp, zstd), outside ASan. Each
// failure must be reported (blvd_stats.load_errors, "out of memory"), cost no
// frame, and leave the runtime usable: the cell is asked for again and loads.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

#include "blvd/blvd.h"
#include "cli/malloc_probe.h"
#include "drive.h"
#include "fault/new_failer.h"
#include "runtime_fixture.h"

namespace {

// Points sampled from a load's allocations: each is a runtime created and a
// cell loaded, 8x slower under AddressSanitizer (CI's sanitizer stage).
#if defined(__SANITIZE_ADDRESS__)
constexpr long kPoints = 20;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr long kPoints = 20;
#else
constexpr long kPoints = 50;
#endif
#else
constexpr long kPoints = 50;
#endif

// Frames a load may take to be uploaded and reported, at the least upload
// budget tried (BLVD_TEST_UPLOAD_MS, below).
constexpr int kFrames = 60;

using blvd_test::baseDesc;
using blvd_test::statsOf;

// Jobs queued by blvd and run when the test says, on the test's thread.
struct ManualExecutor {
  std::vector<std::pair<void (*)(void*), void*>> jobs;
  static void submit(void (*task)(void*), void* arg, void* user) {
    static_cast<ManualExecutor*>(user)->jobs.emplace_back(task, arg);
  }
  void runAll() {
    while (!jobs.empty()) {
      const auto job = jobs.front();
      jobs.erase(jobs.begin());
      job.first(job.second);
    }
  }
};

struct Outcome {
  bool failed = false;   // the failer's n-th allocation came
  long allocations = 0;  // what the failer counted in the loads
  uint64_t load_errors = 0;
  std::string error;
  bool whole = false;  // the pose's frame drawn whole afterwards
};

// A runtime on a host executor at the first pose of an impostor drive: the
// first frame queues the loads, which run under `Failer(fail_at)`; then frames
// and jobs alternate until the frame is whole (the failed cell asked again).
template <class Failer>
Outcome loadUnder(long fail_at) {
  const blvd_test::Drive dr = blvd_test::impostorDrive(2, 8.0);
  ManualExecutor ex;
  ex.jobs.reserve(64);
  blvd_runtime_desc d = baseDesc();
  d.executor = {&ManualExecutor::submit, &ex};
  // A slow machine spreads the uploads over more frames: BLVD_TEST_UPLOAD_MS
  // makes a fast one do the same.
  if (const char* u = std::getenv("BLVD_TEST_UPLOAD_MS")) d.upload_budget_ms = float(std::atof(u));
  blvd_runtime* rt = nullptr;
  Outcome o;
  EXPECT_EQ(blvd_runtime_create(&d, &rt), BLVD_OK) << blvd_last_error(nullptr);
  if (!rt) return o;
  const auto& p = dr.poses.front();
  EXPECT_EQ(blvd_set_pose_local(rt, p.x, p.y, float(p.heading_deg), 0.f), BLVD_OK);
  blvd_frame_stats fs{};
  fs.struct_size = sizeof fs;
  EXPECT_EQ(blvd_render(rt, &fs), BLVD_OK) << blvd_last_error(rt);
  {
    Failer f(fail_at);
    ex.runAll();
    o.failed = f.failed();
    o.allocations = f.count();
  }
  // The failed load may be a prediction's, reported only once the current
  // cell's upload (spread over frames by the upload budget) has finished.
  for (int i = 0; i < kFrames && !(o.whole && (!o.failed || !o.error.empty())); ++i) {
    EXPECT_EQ(blvd_render(rt, &fs), BLVD_OK) << blvd_last_error(rt);
    if (o.error.empty() && statsOf(rt).load_errors > 0) o.error = blvd_last_error(rt);
    o.whole = !(fs.flags & BLVD_FRAME_DEGRADED) && fs.blocks_drawn > 0;
    ex.runAll();
  }
  o.load_errors = statsOf(rt).load_errors;
  ex.runAll();  // destroy waits for every submitted job
  blvd_runtime_destroy(rt);
  return o;
}

template <class Failer>
void everyAllocationOfALoad(const char* what) {
  const Outcome clean = loadUnder<Failer>(-1);
  ASSERT_TRUE(clean.whole);
  ASSERT_EQ(clean.load_errors, 0u) << clean.error;
  const long total = clean.allocations;
  ASSERT_GT(total, 10);
  const bool all = std::getenv("BLVD_FAULT_ALL") != nullptr;
  const long stride = all ? 1 : std::max(1L, total / kPoints);
  long tried = 0;
  for (long n = 0; n < total; n += stride) {
    const Outcome o = loadUnder<Failer>(n);
    if (!o.failed) continue;
    ++tried;
    EXPECT_GE(o.load_errors, 1u) << what << " " << n << " of " << total;
    EXPECT_NE(o.error.find("out of memory"), std::string::npos) << what << " " << n << ": " << o.error;
    EXPECT_TRUE(o.whole) << what << " " << n << ": the cell was not loaded again";
  }
  std::printf("a cell's load: %ld %s of blvd's, %ld failed in turn\n", total, what, tried);
  EXPECT_GT(tried, std::min(total, kPoints) / 2);
}

TEST(LoadFault, EveryCppAllocationOfACellLoadFailingIsReportedAndRetried) {
  everyAllocationOfALoad<blvd_test::NewFailer>("C++ allocations");
}

// The C libraries' calls (stb_image's, libwebp's, zstd's: malloc-family
// calls not through operator new), every one of them.
struct CMallocFailer : blvd::probe::ThreadMallocFailer {
  explicit CMallocFailer(long fail_at) : ThreadMallocFailer(fail_at, true) {}
};

TEST(LoadFault, EveryCAllocationOfACellLoadFailingIsReportedAndRetried) {
  if (!blvd::probe::ThreadMallocCounter::available()) GTEST_SKIP() << "AddressSanitizer owns malloc";
  everyAllocationOfALoad<CMallocFailer>("C allocations (not through operator new)");
}

}  // namespace
