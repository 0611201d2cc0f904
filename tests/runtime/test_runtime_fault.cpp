// Create-time failures of the fixed-memory runtime ("Tests"): a
// budget one byte short fails with the numbers, and a host allocator that
// fails at its Nth call gives BLVD_ERR_NOMEM and leaks nothing. CI runs this
// file under AddressSanitizer + LeakSanitizer too (label asan), so a leak of
// blvd's own heap on any of those error paths fails the run, not only a
// block of the host allocator left live.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "blvd/blvd.h"
#include "fault/new_failer.h"
#include "runtime_fixture.h"

namespace {

using blvd_test::baseDesc;
using blvd_test::Runtime;

TEST(RuntimeMemory, TooSmallABudgetFailsWithTheNumbers) {
  blvd_runtime_desc d = baseDesc();
  uint64_t cpu = 0, gpu = 0;
  ASSERT_EQ(blvd_memory_required(&d, nullptr, &cpu, &gpu), BLVD_OK);
  Runtime r;
  d.memory_budget_bytes = cpu - 1;
  EXPECT_EQ(blvd_runtime_create(&d, &r.rt), BLVD_ERR_BUDGET);
  EXPECT_EQ(r.rt, nullptr);
  const std::string msg = blvd_last_error(nullptr);
  EXPECT_NE(msg.find("package needs"), std::string::npos) << msg;
  EXPECT_NE(msg.find("4 resident cells"), std::string::npos) << msg;
  EXPECT_NE(msg.find("budget is"), std::string::npos) << msg;

  d.memory_budget_bytes = cpu;
  d.gpu_budget_bytes = gpu - 1;
  EXPECT_EQ(blvd_runtime_create(&d, &r.rt), BLVD_ERR_BUDGET);
  EXPECT_NE(std::string(blvd_last_error(nullptr)).find("GPU budget"), std::string::npos);

  d.gpu_budget_bytes = gpu;  // exactly enough
  EXPECT_EQ(blvd_runtime_create(&d, &r.rt), BLVD_OK) << blvd_last_error(nullptr);

  blvd_runtime_desc bad = baseDesc();
  bad.max_resident_cells = 1;
  blvd_runtime* none = nullptr;
  EXPECT_EQ(blvd_runtime_create(&bad, &none), BLVD_ERR_INVALID_ARG);
  bad = baseDesc();
  bad.allocator.alloc = [](size_t, size_t, void*) -> void* { return nullptr; };
  EXPECT_EQ(blvd_runtime_create(&bad, &none), BLVD_ERR_INVALID_ARG);  // alloc without free
  bad = baseDesc();
  bad.prefetch_priority = 7;
  EXPECT_EQ(blvd_runtime_create(&bad, &none), BLVD_ERR_INVALID_ARG);
  EXPECT_NE(std::string(blvd_last_error(nullptr)).find("prefetch_priority"), std::string::npos);
  for (float share : {1.5f, std::nanf("")}) {
    bad = baseDesc();
    bad.prefetch_share = share;
    EXPECT_EQ(blvd_runtime_create(&bad, &none), BLVD_ERR_INVALID_ARG) << share;
    EXPECT_NE(std::string(blvd_last_error(nullptr)).find("prefetch_share"), std::string::npos);
  }
  bad = baseDesc();
  EXPECT_FLOAT_EQ(blvd_runtime_desc_defaults(&bad).prefetch_share, 0.1f);
  bad.prefetch_share = -1;  // no bound: accepted
  Runtime unbounded;
  EXPECT_EQ(blvd_runtime_create(&bad, &unbounded.rt), BLVD_OK) << blvd_last_error(nullptr);
}

// Fails the Nth allocation; counts what is live.
struct FaultyHeap {
  int fail_at = -1;
  int calls = 0;
  int live = 0;
  static void* alloc(size_t size, size_t align, void* user) {
    auto* h = static_cast<FaultyHeap*>(user);
    if (h->calls++ == h->fail_at) return nullptr;
    void* p = std::aligned_alloc(align, (size + align - 1) / align * align);
    if (p) ++h->live;
    return p;
  }
  static void release(void* p, void* user) {
    if (!p) return;
    --static_cast<FaultyHeap*>(user)->live;
    std::free(p);
  }
};

TEST(RuntimeMemory, FailingHostAllocatorGivesNoMemAndLeaksNothing) {
  FaultyHeap heap;
  blvd_runtime_desc d = baseDesc();
  d.allocator = {&FaultyHeap::alloc, &FaultyHeap::release, &heap};
  {
    Runtime r;
    ASSERT_EQ(blvd_runtime_create(&d, &r.rt), BLVD_OK) << blvd_last_error(nullptr);
    EXPECT_GT(heap.live, 0);
  }
  EXPECT_EQ(heap.live, 0);
  const int calls = heap.calls;
  ASSERT_GT(calls, 0);
  for (int n = 0; n < calls; ++n) {
    FaultyHeap h;
    h.fail_at = n;
    d.allocator.user = &h;
    Runtime r;
    EXPECT_EQ(blvd_runtime_create(&d, &r.rt), BLVD_ERR_NOMEM) << "allocation " << n;
    EXPECT_EQ(r.rt, nullptr);
    EXPECT_EQ(h.live, 0) << "allocation " << n << " leaked";
    EXPECT_NE(std::string(blvd_last_error(nullptr)).find("staging"), std::string::npos);
  }
}

// Every C++ allocation blvd makes while creating a runtime (package tables,
// the tracker, the loader, the renderer's pools; not the GL driver's own)
// fails in turn: create returns BLVD_ERR_NOMEM with no runtime, says "out of
// memory", and (under the ASan stage's LeakSanitizer) leaks nothing. The
// allocations are sampled evenly, at most 400 of them, so the test stays
// short; BLVD_FAULT_ALL=1 fails every one.
TEST(RuntimeMemory, EveryAllocationOfCreateFailingGivesNoMem) {
  blvd_runtime_desc d = baseDesc();
  long total = 0;
  {
    blvd_test::NewFailer count(-1);
    Runtime r;
    ASSERT_EQ(blvd_runtime_create(&d, &r.rt), BLVD_OK) << blvd_last_error(nullptr);
    total = count.count();
  }
  ASSERT_GT(total, 10);
  const bool all = std::getenv("BLVD_FAULT_ALL") != nullptr;
  const long stride = all ? 1 : std::max(1L, total / 400);
  long tried = 0;
  for (long n = 0; n < total; n += stride) {
    Runtime r;
    blvd_status st = BLVD_OK;
    bool failed = false;
    {
      blvd_test::NewFailer fail(n);
      st = blvd_runtime_create(&d, &r.rt);
      failed = fail.failed();
    }
    if (!failed) continue;  // this create made fewer allocations (no failure reached)
    ++tried;
    EXPECT_EQ(st, BLVD_ERR_NOMEM) << "allocation " << n << " of " << total << ": " << blvd_last_error(nullptr);
    EXPECT_EQ(r.rt, nullptr) << "allocation " << n;
    EXPECT_NE(std::string(blvd_last_error(nullptr)).find("out of memory"), std::string::npos)
        << "allocation " << n << ": " << blvd_last_error(nullptr);
  }
  std::printf("create: %ld C++ allocations of blvd's on the creating thread, %ld failed in turn\n", total, tried);
  EXPECT_GT(tried, std::min(total, 100L));
  // And a create after all that still works.
  Runtime r;
  EXPECT_EQ(blvd_runtime_create(&d, &r.rt), BLVD_OK) << blvd_last_error(nullptr);
}

}  // namespace
