#include "runtime/frame_clock.h"

#include <algorithm>
#include <cerrno>

#include <time.h>

namespace blvd::runtime {
namespace {

// A decode started this close to a frame's expected start is one the frame
// would share its CPUs with.
constexpr int64_t kMarginNs = 500000;
// "Just after a frame ended": where a unit that fits no gap starts.
constexpr int64_t kJustEndedNs = 1000000;
// How often a waiter looks again while a frame runs past its usual length.
constexpr int64_t kPollNs = 500000;

FrameClock g_clocks[FrameClocks::kMaxClocks];
std::atomic<bool> g_used[FrameClocks::kMaxClocks];

int64_t median(const int64_t* v, int n) {
  int64_t tmp[FrameClock::kWindow];
  std::copy(v, v + n, tmp);
  std::nth_element(tmp, tmp + n / 2, tmp + n);
  return tmp[n / 2];
}

}  // namespace

int64_t monoNs() {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return int64_t(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

void FrameClock::reset() {
  drawing_ = false;
  last_begin_ = last_end_ = period_ = duration_ = 0;
  count_ = 0;
}

void FrameClock::begin(int64_t now_ns) {
  const int64_t prev = last_begin_.load(std::memory_order_relaxed);
  if (prev != 0) intervals_[count_ % kWindow] = now_ns - prev;
  last_begin_.store(now_ns, std::memory_order_relaxed);
  drawing_.store(true, std::memory_order_release);
}

void FrameClock::end(int64_t now_ns) {
  durations_[count_ % kWindow] = now_ns - last_begin_.load(std::memory_order_relaxed);
  last_end_.store(now_ns, std::memory_order_relaxed);
  drawing_.store(false, std::memory_order_release);
  // The first frame has no interval before it: estimates start after kWindow + 1.
  if (++count_ > uint32_t(kWindow)) {
    period_.store(median(intervals_, kWindow), std::memory_order_relaxed);
    duration_.store(median(durations_, kWindow), std::memory_order_relaxed);
  }
}

FrameClock* FrameClocks::acquire() {
  for (int i = 0; i < kMaxClocks; ++i) {
    bool expected = false;
    if (!g_used[i].compare_exchange_strong(expected, true)) continue;
    g_clocks[i].reset();
    return &g_clocks[i];
  }
  return nullptr;
}

void FrameClocks::release(FrameClock* c) {
  if (!c) return;
  g_used[c - g_clocks].store(false);
}

int64_t FrameClocks::decide(int64_t now, int64_t cost_ns) {
  int64_t wake = 0;
  for (int i = 0; i < kMaxClocks; ++i) {
    if (!g_used[i].load(std::memory_order_relaxed)) continue;
    const FrameClock& c = g_clocks[i];
    const int64_t period = c.period(), dur = c.duration();
    if (period <= 0 || period - dur < kMinGapNs) continue;  // too few frames yet, or back to back
    const int64_t begin = c.lastBegin();
    if (now - begin > 2 * period) continue;  // this runtime is not drawing now
    if (c.drawing()) {
      // Look again when the frame should end (or soon, if it runs long).
      wake = std::max(wake, std::max(begin + dur, now + kPollNs));
      continue;
    }
    int64_t next = begin + period;
    if (next <= now) next += ((now - next) / period + 1) * period;
    if (cost_ns + kMarginNs <= next - now) continue;  // fits before the next frame
    const int64_t gap = period - dur;
    if (cost_ns + kMarginNs > gap && now - c.lastEnd() <= kJustEndedNs) continue;  // fits no gap: now is best
    wake = std::max(wake, next + dur);  // right after the next frame
  }
  return wake;
}

int64_t sleepUntilClear(int64_t (*decide)(int64_t now, void* ctx), void* ctx, int64_t max_wait_ns,
                        int64_t max_sleep_ns, bool (*cancel)(void*), void* user) {
  const int64_t start = monoNs();
  for (;;) {
    const int64_t now = monoNs();
    if (now - start >= max_wait_ns || (cancel && cancel(user))) break;
    int64_t wake = decide(now, ctx);
    if (wake == 0) break;
    wake = std::min(wake, start + max_wait_ns);
    if (max_sleep_ns > 0) wake = std::min(wake, now + max_sleep_ns);
    const timespec ts{time_t(wake / 1000000000), long(wake % 1000000000)};
    while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    }
  }
  return monoNs() - start;
}

int64_t FrameClocks::waitForGap(int64_t cost_ns, int64_t max_wait_ns, bool (*cancel)(void*), void* user) {
  auto decideFor = [](int64_t now, void* cost) { return decide(now, *static_cast<int64_t*>(cost)); };
  return sleepUntilClear(decideFor, &cost_ns, max_wait_ns, 0, cancel, user);
}

}  // namespace blvd::runtime
