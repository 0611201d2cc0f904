// A bound on the CPU time predicted cells take from frames drawn back to back
// (docs/decisions/0008 §14).
//
// A host that draws back to back leaves no gap for FrameClocks to place a
// mesh in, and on a CPU renderer every core is then busy with the frame: a
// prediction's decode, SCHED_IDLE or not, lands inside some frame and slows
// its rasterizers (§10). A cell's decode started at a cell boundary lands in
// the next few frames all at once. The bucket spreads it instead: the
// process's prediction threads together may spend `share` of the wall time
// (a token bucket, Turner 1986: tokens accrue at `share` per nanosecond up
// to `burst_ns`; a mesh starts when the tokens cover its estimated cost, or
// the whole burst for a mesh larger than that, and its measured CPU time is
// then taken out, possibly into debt). At the default share every frame
// carries a little of the decode rather than a few frames carrying all of it.
//
// Fixed memory; the process-wide bucket is a static with a mutex, taken by
// prediction threads only (never the render thread).
#pragma once
#include <cstdint>

namespace blvd::runtime {

class ShareBucket {
 public:
  // 0: a unit estimated at `cost_ns` may start at `now`; otherwise the
  // absolute time at which it may. Accrues up to `now` first.
  int64_t decide(int64_t now, int64_t cost_ns, double share, int64_t burst_ns);
  // A unit ran for `cpu_ns` of CPU time.
  void charge(int64_t now, int64_t cpu_ns, double share, int64_t burst_ns);
  double tokens() const { return tokens_; }

 private:
  void accrue(int64_t now, double share, int64_t burst_ns);
  double tokens_ = 0;  // nanoseconds; negative: debt
  int64_t last_ = 0;   // 0: never used (the first call starts with a full burst)
};

namespace prefetch_share {
// The largest tokens the bucket holds: the most a prediction may take in one
// go after a pause. A Monaco block level decodes in 0.09 ms at p50 and an
// impostor layer in 0.15 ms (`blvd bench decode`, decision 0009), so a
// whole cell (≈ 1 ms) no longer fits into the frame that entered it.
inline constexpr int64_t kBurstNs = 250000;
// Process-wide: waits (sleeping, looking at `cancel` every millisecond) until
// a unit of `cost_ns` may start, at most `max_wait_ns`. Returns the
// nanoseconds waited. share <= 0: returns at once.
int64_t wait(int64_t cost_ns, double share, int64_t max_wait_ns, bool (*cancel)(void*), void* user);
void charge(int64_t cpu_ns, double share);
}  // namespace prefetch_share

}  // namespace blvd::runtime
