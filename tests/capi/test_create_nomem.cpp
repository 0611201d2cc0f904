// Every C++ allocation blvd makes while opening a package's tables
// (blvd_memory_required), creating a tracker over a package (the graph tables,
// the matcher, the filter) and creating a CAN profile (the DBC parsed, the
// signals bound) fails in turn: the call returns BLVD_ERR_NOMEM, gives no
// object, says "out of memory", and (under the ASan stage's LeakSanitizer)
// leaks nothing. The runtime's create has its own test (test_runtime_fault).
// At most 400 failure points per call (100 under ASan and 50 on arm64, where
// a DBC's parse is slow), evenly spread; BLVD_FAULT_ALL=1 fails every one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "blvd/blvd.h"
#include "fault/new_failer.h"

namespace {

#if defined(__SANITIZE_ADDRESS__)
constexpr long kPoints = 100;
#elif defined(__aarch64__)
constexpr long kPoints = 50;  // CI's arm64 stage runs under qemu-aarch64: a DBC's parse takes 0.6 s there
#else
constexpr long kPoints = 400;
#endif

// create() makes and frees the object, returning its create's status.
template <class Create>
void failEachAllocation(const char* what, Create&& create) {
  long total = 0;
  {
    blvd_test::NewFailer count(-1);
    ASSERT_EQ(create(), BLVD_OK) << what << ": " << blvd_last_error(nullptr);
    total = count.count();
  }
  ASSERT_GT(total, 10) << what;
  const long stride = std::getenv("BLVD_FAULT_ALL") ? 1 : std::max(1L, total / kPoints);
  long tried = 0;
  for (long n = 0; n < total; n += stride) {
    blvd_status st = BLVD_OK;
    bool failed = false;
    {
      blvd_test::NewFailer fail(n);
      st = create();
      failed = fail.failed();
    }
    if (!failed) continue;  // this call made fewer allocations
    ++tried;
    EXPECT_EQ(st, BLVD_ERR_NOMEM) << what << ": allocation " << n << " of " << total << ": " << blvd_last_error(nullptr);
    EXPECT_NE(std::string(blvd_last_error(nullptr)).find("out of memory"), std::string::npos)
        << what << ": allocation " << n << ": " << blvd_last_error(nullptr);
  }
  std::printf("%s: %ld C++ allocations, %ld failed in turn\n", what, total, tried);
  EXPECT_GE(tried, std::min(total, std::min(100L, kPoints))) << what;
  EXPECT_EQ(create(), BLVD_OK) << what << " after the failures: " << blvd_last_error(nullptr);
}

TEST(CreateNoMem, OpeningAPackagesTables) {
  failEachAllocation("blvd_memory_required", [] {
    blvd_runtime_desc d{};
    d.struct_size = sizeof d;
    uint64_t cpu = 0, gpu = 0;
    return blvd_memory_required(&d, BLVD_TEST_PACKAGE, &cpu, &gpu);
  });
}

TEST(CreateNoMem, ATrackerOverAPackage) {
  failEachAllocation("blvd_tracker_create", [] {
    blvd_tracker_desc d{};
    d.struct_size = sizeof d;
    d.package_path = BLVD_TEST_PACKAGE;
    blvd_tracker* tr = nullptr;
    const blvd_status st = blvd_tracker_create(&d, &tr);
    EXPECT_EQ(tr != nullptr, st == BLVD_OK);
    blvd_tracker_destroy(tr);
    return st;
  });
}

TEST(CreateNoMem, ACanProfile) {
  const std::string dbc = std::string(BLVD_TEST_DATA_DIR) + "/can/dbc/vw_mqb.dbc";
  failEachAllocation("blvd_can_profile_create", [&] {
    blvd_can_profile_desc d{};
    d.struct_size = sizeof d;
    d.vehicle = BLVD_VEHICLE_VW_MQB;
    d.dbc_path = dbc.c_str();
    blvd_can_profile* p = nullptr;
    const blvd_status st = blvd_can_profile_create(&d, &p);
    EXPECT_EQ(p != nullptr, st == BLVD_OK);
    blvd_can_profile_destroy(p);
    return st;
  });
}

}  // namespace
