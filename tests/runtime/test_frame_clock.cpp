// FrameClocks (docs/decisions/0008 §11): when a predicted mesh may start, given
// the frames of the process's runtimes. Synthetic clocks, no GL, no sleeping
// except in the waitForGap cases.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>

#include "runtime/frame_clock.h"

namespace {

using blvd::runtime::FrameClock;
using blvd::runtime::FrameClocks;

constexpr int64_t kMs = 1000000;

// Draws `n` frames of `dur` every `period` from `t0`; returns the last start.
int64_t drive(FrameClock& c, int64_t t0, int64_t period, int64_t dur, int n) {
  int64_t t = t0;
  for (int i = 0; i < n; ++i, t += period) {
    c.begin(t);
    c.end(t + dur);
  }
  return t - period;
}

struct Held {
  FrameClock* c = FrameClocks::acquire();
  ~Held() { FrameClocks::release(c); }
};

// The render thread stamps frames from its steady_clock reads: the same clock.
TEST(FrameClock, SteadyClockIsMonotonicNs) {
  const int64_t a = blvd::runtime::monoNs(std::chrono::steady_clock::now());
  const int64_t b = blvd::runtime::monoNs();
  EXPECT_LE(a, b);
  EXPECT_LT(b - a, 50 * kMs);
}

TEST(FrameClock, MediansNeedAFullWindow) {
  Held h;
  ASSERT_NE(h.c, nullptr);
  drive(*h.c, 1000 * kMs, 16 * kMs, 5 * kMs, FrameClock::kWindow);
  EXPECT_EQ(h.c->period(), 0);  // kWindow frames give kWindow - 1 intervals
  drive(*h.c, 1000 * kMs + FrameClock::kWindow * 16 * kMs, 16 * kMs, 5 * kMs, 1);
  EXPECT_EQ(h.c->period(), 16 * kMs);
  EXPECT_EQ(h.c->duration(), 5 * kMs);
}

TEST(FrameClock, MedianIgnoresAMissedTickAndALongFrame) {
  Held h;
  int64_t t = 1000 * kMs;
  for (int i = 0; i < 40; ++i) {
    const bool odd = i % 10 == 7;
    h.c->begin(t);
    h.c->end(t + (odd ? 20 * kMs : 5 * kMs));
    t += odd ? 32 * kMs : 16 * kMs;
  }
  EXPECT_EQ(h.c->period(), 16 * kMs);
  EXPECT_EQ(h.c->duration(), 5 * kMs);
}

TEST(FrameClocks, NoClockOrTooFewFramesMeansGo) {
  EXPECT_EQ(FrameClocks::decide(5000 * kMs, 3 * kMs), 0);
  Held h;
  h.c->begin(5000 * kMs);  // drawing, but no period known yet
  EXPECT_EQ(FrameClocks::decide(5001 * kMs, 3 * kMs), 0);
}

TEST(FrameClocks, BackToBackFramesAreNotScheduledAround) {
  Held h;
  const int64_t last = drive(*h.c, 1000 * kMs, 4 * kMs, 4 * kMs - 100000, 40);
  h.c->begin(last + 4 * kMs);  // drawing now
  EXPECT_EQ(FrameClocks::decide(last + 5 * kMs, 10 * kMs), 0);
}

TEST(FrameClocks, PacedFramesGetTheirGapsUsed) {
  Held h;
  const int64_t P = 16 * kMs, D = 5 * kMs;
  const int64_t last = drive(*h.c, 1000 * kMs, P, D, 40);
  const int64_t next = last + P;
  // Just after a frame ended: a 3 ms mesh fits before the next frame.
  EXPECT_EQ(FrameClocks::decide(last + D + kMs / 10, 3 * kMs), 0);
  // Late in the gap it does not: look again when the next frame should end.
  EXPECT_EQ(FrameClocks::decide(next - 2 * kMs, 3 * kMs), next + D);
  // A mesh that fits no gap starts right after a frame ends, not later.
  EXPECT_EQ(FrameClocks::decide(last + D + kMs / 10, 30 * kMs), 0);
  EXPECT_EQ(FrameClocks::decide(last + D + 4 * kMs, 30 * kMs), next + D);
  // While a frame draws: wait for its expected end.
  h.c->begin(next);
  EXPECT_EQ(FrameClocks::decide(next + kMs, 1), next + D);
  // A frame running past its usual length: look again soon.
  const int64_t late = next + D + 2 * kMs;
  const int64_t w = FrameClocks::decide(late, 1);
  EXPECT_GT(w, late);
  EXPECT_LE(w, late + kMs);
  h.c->end(late);
  // A runtime that stopped drawing (more than two periods ago) holds nothing.
  EXPECT_EQ(FrameClocks::decide(next + 3 * P, 30 * kMs), 0);
}

TEST(FrameClocks, AnyRuntimeDrawingHoldsTheMesh) {
  Held a, b;
  const int64_t P = 16 * kMs, D = 5 * kMs;
  const int64_t last_a = drive(*a.c, 1000 * kMs, P, D, 40);
  drive(*b.c, 1000 * kMs + 8 * kMs, P, D, 39);  // b draws in a's gaps, its last frame before a's
  // Between a's end and b's start (3 ms) a 2 ms mesh fits, a 5 ms one does not.
  const int64_t t = last_a + D + kMs / 10;
  EXPECT_EQ(FrameClocks::decide(t, 2 * kMs), 0);
  EXPECT_GT(FrameClocks::decide(t, 5 * kMs), t);
}

TEST(FrameClocks, ReleasedClocksStopCounting) {
  int64_t last = 0;
  {
    Held h;
    last = drive(*h.c, 1000 * kMs, 16 * kMs, 5 * kMs, 40);
    h.c->begin(last + 16 * kMs);
    EXPECT_GT(FrameClocks::decide(last + 17 * kMs, kMs), 0);
  }
  EXPECT_EQ(FrameClocks::decide(last + 17 * kMs, kMs), 0);
}

TEST(FrameClocks, TableFullMeansUnregistered) {
  FrameClock* got[FrameClocks::kMaxClocks + 1] = {};
  int n = 0;
  while (n <= FrameClocks::kMaxClocks && (got[n] = FrameClocks::acquire()) != nullptr) ++n;
  EXPECT_EQ(n, FrameClocks::kMaxClocks);
  for (int i = 0; i < n; ++i) FrameClocks::release(got[i]);
  Held h;
  EXPECT_NE(h.c, nullptr);
}

TEST(FrameClocks, WaitForGapEndsOnCancelAndOnItsBound) {
  Held h;
  // A frame that started now and "draws" for ever: every decision says wait.
  const int64_t now = blvd::runtime::monoNs();
  drive(*h.c, now - 40 * 16 * kMs, 16 * kMs, 5 * kMs, 40);
  h.c->begin(blvd::runtime::monoNs());
  const int64_t waited = FrameClocks::waitForGap(kMs, 20 * kMs, nullptr, nullptr);
  EXPECT_GE(waited, 20 * kMs);
  EXPECT_LT(waited, 200 * kMs);
  auto yes = [](void*) { return true; };
  EXPECT_LT(FrameClocks::waitForGap(kMs, 1000 * kMs, yes, nullptr), 20 * kMs);
}

}  // namespace
