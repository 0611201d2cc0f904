// The prediction's share of the wall time (docs/decisions/0008 §14): a token
// bucket over synthetic time, and the process-wide wait with a real clock.
#include <gtest/gtest.h>

#include <cstdint>

#include "runtime/frame_clock.h"
#include "runtime/prefetch_share.h"

namespace {

using blvd::runtime::ShareBucket;
constexpr int64_t kMs = 1000000;
constexpr int64_t kBurst = 2 * kMs;

TEST(ShareBucket, StartsWithAFullBurst) {
  ShareBucket b;
  EXPECT_EQ(b.decide(100 * kMs, kBurst, 0.1, kBurst), 0);
  EXPECT_DOUBLE_EQ(b.tokens(), double(kBurst));
}

TEST(ShareBucket, ACostlyUnitWaitsForItsTokens) {
  ShareBucket b;
  const int64_t t0 = 100 * kMs;
  ASSERT_EQ(b.decide(t0, kMs, 0.1, kBurst), 0);
  // 1 ms of wall, 2 ms of CPU (two threads): the full bucket accrues nothing
  // past its burst, and the 2 ms empty it; 1 ms more takes 10 ms at 10 %.
  b.charge(t0 + kMs, 2 * kMs, 0.1, kBurst);
  EXPECT_NEAR(b.tokens(), 0, 1);
  const int64_t wake = b.decide(t0 + kMs, kMs, 0.1, kBurst);
  EXPECT_NEAR(double(wake - (t0 + kMs)), 10.0 * kMs, 2);
  EXPECT_NE(b.decide(wake - kMs / 10, kMs, 0.1, kBurst), 0) << "not yet";
  EXPECT_EQ(b.decide(wake, kMs, 0.1, kBurst), 0);
}

// The smallest share a float holds: the wait is long, but an int64 of
// nanoseconds holds it (it overflowed, undefined behaviour, before).
TEST(ShareBucket, ATinyShareWaitsLongWithoutOverflow) {
  ShareBucket b;
  const int64_t t0 = 100 * kMs;
  const double share = double(1e-45f);
  ASSERT_EQ(b.decide(t0, kMs, share, kBurst), 0);
  b.charge(t0, 100 * kMs, share, kBurst);
  const int64_t wake = b.decide(t0, kMs, share, kBurst);
  EXPECT_GT(wake, t0 + 1000 * kMs);
  EXPECT_LT(wake, t0 + 4000000 * kMs);
}

TEST(ShareBucket, TokensNeverExceedTheBurst) {
  ShareBucket b;
  ASSERT_EQ(b.decide(kMs, 0, 0.5, kBurst), 0);
  ASSERT_EQ(b.decide(10000 * kMs, 0, 0.5, kBurst), 0);
  EXPECT_DOUBLE_EQ(b.tokens(), double(kBurst));
}

// A unit costlier than the whole burst starts once the burst is full, and the
// debt it leaves holds the next one back: on average the share holds.
TEST(ShareBucket, AUnitLargerThanTheBurstRunsIntoDebtAndTheAverageHolds) {
  ShareBucket b;
  const double share = 0.1;
  int64_t t = 50 * kMs, cpu = 0;
  const int64_t start = t;
  for (int i = 0; i < 200; ++i) {
    const int64_t cost = (i % 5 == 0) ? 6 * kMs : kMs / 2;  // an impostor now and then
    for (int64_t w; (w = b.decide(t, cost, share, kBurst)) != 0;) t = w;
    t += cost;  // runs alone: wall = CPU
    b.charge(t, cost, share, kBurst);
    cpu += cost;
  }
  const double used = double(cpu) / double(t - start);
  EXPECT_LE(used, share * 1.05 + double(kBurst) / double(t - start));
  EXPECT_GE(used, share * 0.9);
}

TEST(ShareBucket, NoShareMeansNoBound) {
  ShareBucket b;
  EXPECT_EQ(b.decide(kMs, 100 * kMs, 0, kBurst), 0);
  b.charge(2 * kMs, 100 * kMs, 0, kBurst);
  EXPECT_EQ(b.decide(3 * kMs, 100 * kMs, 0, kBurst), 0);
}

// The process-wide bucket, on the real clock: ten 1 ms units at a 20 % share
// take about 50 ms of wall time (less the bucket's burst), and a cancelled wait
// returns at once.
TEST(PrefetchShare, ProcessWideWaitPacesUnits) {
  using namespace blvd::runtime;
  const int64_t t0 = monoNs();
  for (int i = 0; i < 10; ++i) {
    prefetch_share::wait(kMs, 0.2, 1000 * kMs, nullptr, nullptr);
    prefetch_share::charge(kMs, 0.2);
  }
  const double ms = double(monoNs() - t0) / kMs;
  EXPECT_GE(ms, 30.0);
  EXPECT_LT(ms, 2000.0);
  auto yes = [](void*) { return true; };
  prefetch_share::charge(50 * kMs, 0.2);  // deep in debt
  EXPECT_LT(prefetch_share::wait(kMs, 0.2, 1000 * kMs, yes, nullptr), 100 * kMs);
  EXPECT_EQ(prefetch_share::wait(kMs, 0, 1000 * kMs, nullptr, nullptr), 0);
}

}  // namespace
