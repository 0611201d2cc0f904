// Prefetch planned by the link; the contract is in link_prefetch.h.
#include "runtime/link_prefetch.h"

#include <algorithm>

namespace blvd::runtime {

LinkPrefetch::LinkPrefetch(const stream::City& city) : city_(city), remote_(city.remote()) {
  if (!remote_) return;
  next_.reserve(kMaxCells);
  wanted_.reserve(64);
  walk_.reserve(kMaxCells);
  const uint64_t blobs = remote_->blobCount() ? remote_->blobCount() : 1;
  uint64_t total = 0;
  for (uint32_t i = 0; i < remote_->blobCount(); ++i) total += remote_->blobInfo(i).size;
  // A cell's bytes, roughly: its blobs' share (local blocks and layers, a dozen or two).
  avg_cell_bytes_ = double(total) / double(blobs) * 12.0;
  thread_ = std::thread([this] { run(); });
}

LinkPrefetch::~LinkPrefetch() {
  if (!thread_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

void LinkPrefetch::plan(uint32_t cell, const stream::Residency& residency, double speed_mps) {
  if (!remote_ || cell == graph::kNone) return;
  const double measured = remote_->throughput();
  const double throughput = measured > 0 ? measured : 1e5;
  const double horizon_s = kOutageS + 2.0 * avg_cell_bytes_ / throughput;
  const double horizon = std::max(kMinAheadM, speed_mps * horizon_s);
  horizon_m_.store(horizon, std::memory_order_relaxed);
  walk_.clear();
  double metres = 0;
  for (uint32_t c = cell; c != graph::kNone && walk_.size() < kMaxCells && metres < horizon;
       c = residency.nextOnRoute(c)) {
    if (std::find(walk_.begin(), walk_.end(), c) != walk_.end()) break;  // a looping route: once round
    walk_.push_back(c);
    metres += city_.streets().halfedge(c).length;
  }
  for (size_t r = walk_.size() == 1 ? 1 : residency.wantedCount(); r < residency.wantedCount(); ++r)
    walk_.push_back(residency.wanted()[r]);  // off the route: the predicted cells
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (next_.empty() || next_.front() != walk_.front()) ++plan_id_;
    next_.assign(walk_.begin(), walk_.end());
    wanted_.assign(residency.wanted(), residency.wanted() + residency.wantedCount());
  }
  cv_.notify_one();
}

bool LinkPrefetch::cellCached(uint32_t cell, std::vector<uint32_t>& scratch) const {
  city_.cellBlobs(cell, nullptr, 0, scratch);
  return std::all_of(scratch.begin(), scratch.end(), [&](uint32_t b) { return remote_->cached(b); });
}

double LinkPrefetch::measureAhead(const std::vector<uint32_t>& cells, std::vector<uint32_t>& scratch) const {
  double m = 0;
  for (const uint32_t c : cells) {
    if (!cellCached(c, scratch)) break;
    m += city_.streets().halfedge(c).length;
  }
  return m;
}

void LinkPrefetch::run() {
  std::vector<uint32_t> cells, wanted, scratch;
  uint64_t seen = ~0ull;
  std::string err;
  auto last_request = std::chrono::steady_clock::now();
  uint64_t last_requests = 0;
  for (;;) {
    uint64_t id = 0;
    {
      std::unique_lock<std::mutex> lock(mu_);
      cv_.wait_for(lock, std::chrono::milliseconds(500), [&] { return stop_ || plan_id_ != seen; });
      if (stop_) return;
      cells = next_;
      wanted = wanted_;
      seen = id = plan_id_;
    }
    const uint64_t budget = remote_->stats().cache_bytes_max / 2;
    uint64_t planned = 0;
    for (const uint32_t c : cells) {
      if (remote_->mode() != remote::LinkMode::Online || remote_->changed()) break;
      {
        std::lock_guard<std::mutex> lock(mu_);
        if (stop_ || plan_id_ != id) break;  // the vehicle moved on: plan again from its cell
      }
      if (std::find(wanted.begin(), wanted.end(), c) != wanted.end()) continue;  // the loader fetches it
      city_.cellBlobs(c, nullptr, 0, scratch);
      for (const uint32_t b : scratch) planned += remote_->blobInfo(b).size;
      if (planned > budget) break;
      if (remote_->fetchBlobs(scratch.data(), scratch.size(), err, true) != core::Status::Ok) break;  // the link: later
      cached_ahead_m_.store(measureAhead(cells, scratch), std::memory_order_relaxed);
    }
    cached_ahead_m_.store(measureAhead(cells, scratch), std::memory_order_relaxed);
    const uint64_t requests = remote_->stats().link.requests;
    if (requests != last_requests) {
      last_requests = requests, last_request = std::chrono::steady_clock::now();
    } else if (remote_->mode() == remote::LinkMode::Online && !remote_->changed() &&
               std::chrono::steady_clock::now() - last_request > std::chrono::duration<double>(kRevalidateS)) {
      remote_->revalidate(err);
      last_request = std::chrono::steady_clock::now();
    }
  }
}

}  // namespace blvd::runtime
