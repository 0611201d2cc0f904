#include "runtime/prefetch_share.h"

#include <algorithm>
#include <mutex>

#include "runtime/frame_clock.h"

namespace blvd::runtime {

void ShareBucket::accrue(int64_t now, double share, int64_t burst_ns) {
  if (last_ == 0) tokens_ = double(burst_ns);
  else if (now > last_) tokens_ = std::min(double(burst_ns), tokens_ + share * double(now - last_));
  last_ = std::max(last_, now);
}

int64_t ShareBucket::decide(int64_t now, int64_t cost_ns, double share, int64_t burst_ns) {
  if (share <= 0) return 0;
  accrue(now, share, burst_ns);
  const double need = double(std::min(std::max<int64_t>(cost_ns, 0), burst_ns));
  if (tokens_ >= need) return 0;
  // A share as small as a float gets (1e-45) would wait past what int64
  // holds; no wait is longer than the caller's cap, so an hour will do.
  const double wait_ns = std::min((need - tokens_) / share, 3.6e12);
  return now + std::max<int64_t>(1, int64_t(wait_ns) + 1);
}

void ShareBucket::charge(int64_t now, int64_t cpu_ns, double share, int64_t burst_ns) {
  if (share <= 0) return;
  accrue(now, share, burst_ns);
  tokens_ -= double(std::max<int64_t>(cpu_ns, 0));
}

namespace prefetch_share {
namespace {
std::mutex g_mu;
ShareBucket g_bucket;
constexpr int64_t kLookNs = 1000000;
}  // namespace

int64_t wait(int64_t cost_ns, double share, int64_t max_wait_ns, bool (*cancel)(void*), void* user) {
  if (share <= 0) return 0;
  struct Ask {
    int64_t cost;
    double share;
  } ask{cost_ns, share};
  auto decide = [](int64_t now, void* p) {
    const Ask& a = *static_cast<const Ask*>(p);
    std::lock_guard<std::mutex> lock(g_mu);
    return g_bucket.decide(now, a.cost, a.share, kBurstNs);
  };
  return sleepUntilClear(decide, &ask, max_wait_ns, kLookNs, cancel, user);
}

void charge(int64_t cpu_ns, double share) {
  if (share <= 0) return;
  const int64_t now = monoNs();
  std::lock_guard<std::mutex> lock(g_mu);
  g_bucket.charge(now, cpu_ns, share, kBurstNs);
}

}  // namespace prefetch_share
}  // namespace blvd::runtime
