// When the process's runtimes draw, so that prediction decoding can go into
// the gaps between frames (docs/decisions/0008 §11).
//
// A host that draws at a display's refresh leaves the CPU idle between the end
// of one frame and the start of the next. A SCHED_IDLE decoder already runs
// only in idle time as the guest scheduler sees it, but a Draco mesh takes
// 4-14 ms: started late in a gap it runs on into the next frame, and the
// frame's rasterizer threads then share caches, memory bandwidth and (on a VM)
// host cores with it. So each runtime registers a FrameClock; the render
// thread stamps every frame's start and end (two atomic stores, a clock read
// it makes anyway), and a background decoder asks FrameClocks::waitForGap()
// before each mesh: it waits while any registered runtime draws, and starts a
// mesh only when its estimated cost fits before the next expected frame start.
// A mesh that fits no gap starts right after a frame ends (the most room it
// can get). Hosts that draw back to back (no gap) are left alone: the decoder
// runs as before, under SCHED_IDLE only.
//
// Fixed memory: a process-wide table of kMaxClocks slots, no allocation. A
// runtime that finds the table full simply is not waited for.
#pragma once
#include <atomic>
#include <chrono>
#include <cstdint>

namespace blvd::runtime {

int64_t monoNs();  // CLOCK_MONOTONIC in nanoseconds
// A steady_clock time in the same nanoseconds (libstdc++'s steady_clock is
// CLOCK_MONOTONIC), so a caller that already read the clock need not again.
inline int64_t monoNs(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
}

// The background waits' one loop (FrameClocks::waitForGap, prefetch_share::wait):
// sleeps until `decide(now, ctx)` returns 0 (otherwise it returns the absolute
// time to look again), `cancel(user)` says so, or `max_wait_ns` has passed.
// No sleep is longer than `max_sleep_ns` (0: no cap), so that a cancel is seen.
// Returns the nanoseconds waited.
int64_t sleepUntilClear(int64_t (*decide)(int64_t now, void* ctx), void* ctx, int64_t max_wait_ns,
                        int64_t max_sleep_ns, bool (*cancel)(void*), void* user);

class FrameClock {
 public:
  // Forgets every frame (a slot handed to a new runtime).
  void reset();
  // Render thread.
  void begin(int64_t now_ns);
  void end(int64_t now_ns);

  // Any thread: a consistent-enough view (each field is atomic; a torn pair
  // only shifts one wait by a frame).
  bool drawing() const { return drawing_.load(std::memory_order_acquire); }
  int64_t lastBegin() const { return last_begin_.load(std::memory_order_relaxed); }
  int64_t lastEnd() const { return last_end_.load(std::memory_order_relaxed); }
  // Median of the last kWindow start-to-start intervals and frame durations;
  // 0 until kWindow frames were drawn.
  int64_t period() const { return period_.load(std::memory_order_relaxed); }
  int64_t duration() const { return duration_.load(std::memory_order_relaxed); }

  static constexpr int kWindow = 15;

 private:
  std::atomic<bool> drawing_{false};
  std::atomic<int64_t> last_begin_{0}, last_end_{0}, period_{0}, duration_{0};
  // Render thread only.
  int64_t intervals_[kWindow] = {}, durations_[kWindow] = {};
  uint32_t count_ = 0;
};

// The process's registered clocks.
class FrameClocks {
 public:
  static constexpr int kMaxClocks = 16;
  // Gaps shorter than this are not scheduled around (frames back to back).
  static constexpr int64_t kMinGapNs = 1000000;

  // A slot, or nullptr when every slot is taken.
  static FrameClock* acquire();
  static void release(FrameClock* c);

  // Background thread, before a unit of work estimated to take `cost_ns`:
  // returns when it may start (see the file comment), or when `cancel()`
  // says so, or after waiting `max_wait_ns`. Returns the nanoseconds waited.
  static int64_t waitForGap(int64_t cost_ns, int64_t max_wait_ns, bool (*cancel)(void*), void* user);

  // For the unit tests: what waitForGap decides at time `now` without
  // sleeping. 0: start now; otherwise the absolute time to look again.
  static int64_t decide(int64_t now, int64_t cost_ns);
};

}  // namespace blvd::runtime
