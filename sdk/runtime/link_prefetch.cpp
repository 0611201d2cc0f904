// Prefetch planned by the link; the contract is in link_prefetch.h.
#include "runtime/link_prefetch.h"

#include <algorithm>

#include <glm/geometric.hpp>

namespace blvd::runtime {
namespace {

// Without a route: the successor that goes straightest on (no U-turn), the
// likeliest way ahead; kNone at a dead end.
uint32_t straightOn(const graph::GraphSource& g, uint32_t c) {
  const glm::dvec2 d = graph::cellDirection(g, c, true);
  const uint32_t twin = g.halfedge(c).twin;
  uint32_t best = graph::kNone;
  double best_cos = -2;
  for (const uint32_t s : g.successors(c)) {
    if (s == twin) continue;
    const double k = glm::dot(d, graph::cellDirection(g, s, false));
    if (k > best_cos) best_cos = k, best = s;
  }
  return best;
}

}  // namespace

LinkPrefetch::LinkPrefetch(const stream::City& city) : city_(city), remote_(city.remote()) {
  if (!remote_) return;
  next_.reserve(kMaxCells);
  ways_.reserve(kMaxCells + 1);
  wanted_.reserve(64);
  terrain_.reserve(kMaxTerrain);
  walk_.reserve(kMaxCells);
  const uint64_t blobs = remote_->blobCount() ? remote_->blobCount() : 1;
  uint64_t total = 0;
  for (uint32_t i = 0; i < remote_->blobCount(); ++i) total += remote_->blobInfo(i).size;
  // A cell's bytes, roughly: its blobs' share (local blocks and layers, a dozen or two).
  avg_cell_bytes_ = double(total) / double(blobs) * 12.0;
  remote_->onTablesWanted([this] { cv_.notify_one(); });
  thread_ = std::thread([this] { run(); });
}

LinkPrefetch::~LinkPrefetch() {
  if (!thread_.joinable()) return;
  remote_->onTablesWanted(nullptr);
  {
    std::lock_guard<std::mutex> lock(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

// Without a route, every way ahead breadth first (Marvie et al.: the
// neighbours first), each while its start lies within the horizon.
void LinkPrefetch::addWaysAhead(uint32_t cell, double horizon) {
  ways_.clear();
  ways_.push_back({cell, 0.0});
  for (size_t at = 0; at < ways_.size() && walk_.size() < kMaxCells; ++at) {
    const auto [c, start] = ways_[at];
    const double end = start + city_.streets().halfedge(c).length;
    if (end >= horizon) continue;
    const uint32_t twin = city_.streets().halfedge(c).twin;
    for (const uint32_t s : city_.streets().successors(c)) {
      if (s == twin || walk_.size() >= kMaxCells ||
          std::any_of(ways_.begin(), ways_.end(), [&](const std::pair<uint32_t, double>& w) { return w.first == s; }))
        continue;
      ways_.push_back({s, end});
      if (std::find(walk_.begin(), walk_.end(), s) == walk_.end()) walk_.push_back(s);  // the road has it already
    }
  }
}

void LinkPrefetch::plan(uint32_t cell, const stream::Residency& residency, double speed_mps) {
  if (!remote_ || cell == graph::kNone) return;
  // Again when the vehicle enters another cell, and now and then for a new horizon.
  if (cell == planned_cell_ && ++frames_since_plan_ < 32) return;
  planned_cell_ = cell, frames_since_plan_ = 0;
  try {
    planFrom(cell, residency, speed_mps);
  } catch (const core::Error& e) {
    // The road ahead's table pages are on their way (a frame never waits for
    // them): planned again next frame.
    if (e.status() != core::Status::Unavailable) throw;
    planned_cell_ = graph::kNone;
  }
}

void LinkPrefetch::planFrom(uint32_t cell, const stream::Residency& residency, double speed_mps) {
  const double measured = remote_->throughput();
  const double throughput = measured > 0 ? measured : 1e5;
  const double horizon_s = kOutageS + 2.0 * avg_cell_bytes_ / throughput;
  const double horizon = std::max(kMinAheadM, speed_mps * horizon_s);
  horizon_m_.store(horizon, std::memory_order_relaxed);
  walk_.clear();
  double metres = 0;
  const bool route = residency.hasRoute();
  for (uint32_t c = cell; c != graph::kNone && walk_.size() < kMaxCells && metres < horizon;
       c = route ? residency.nextOnRoute(c) : straightOn(city_.streets(), c)) {
    if (std::find(walk_.begin(), walk_.end(), c) != walk_.end()) break;  // a looping route: once round
    walk_.push_back(c);
    metres += city_.streets().halfedge(c).length;
  }
  const size_t road = walk_.size();
  for (size_t r = 1; r < residency.wantedCount(); ++r)  // the slots' predictions (other turns) too
    if (std::find(walk_.begin(), walk_.end(), residency.wanted()[r]) == walk_.end()) walk_.push_back(residency.wanted()[r]);
  if (!route) addWaysAhead(cell, horizon);
  {
    std::lock_guard<std::mutex> lock(mu_);
    road_n_ = road;
    if (next_.empty() || next_.front() != walk_.front()) ++plan_id_;
    next_.assign(walk_.begin(), walk_.end());
    wanted_.assign(residency.wanted(), residency.wanted() + residency.wantedCount());
  }
  cv_.notify_one();
}

void LinkPrefetch::wantTerrain(const std::vector<uint32_t>& blobs) {
  if (!remote_) return;
  const size_t n = std::min(blobs.size(), kMaxTerrain);
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (terrain_.size() == n && std::equal(blobs.begin(), blobs.begin() + n, terrain_.begin())) return;
    terrain_.assign(blobs.begin(), blobs.begin() + n);
    terrain_new_ = n > 0;
  }
  if (n) cv_.notify_one();
}

double LinkPrefetch::measureAhead(const std::vector<uint32_t>& cells, size_t road, std::vector<uint32_t>& scratch) const {
  double m = 0;
  for (size_t i = 0; i < road && i < cells.size(); ++i) {
    if (!city_.cellCached(cells[i], scratch)) break;
    m += city_.streets().halfedge(cells[i]).length;
  }
  return m;
}

// The blobs of `cells` not wanted by the slots, in order, until the plan
// changes, the link refuses or half the blob cache is planned.
void LinkPrefetch::fetchAhead(const std::vector<uint32_t>& cells, const std::vector<uint32_t>& wanted, size_t road,
                              uint64_t id, std::vector<uint32_t>& scratch, std::string& err) {
  const uint64_t budget = remote_->stats().cache_bytes_max / 2;
  uint64_t planned = 0;
  for (const uint32_t c : cells) {
    if (remote_->mode() != remote::LinkMode::Online || remote_->changed()) break;
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (stop_ || plan_id_ != id) break;  // the vehicle moved on: plan again from its cell
    }
    city_.warmCell(c);  // what a frame there reads of the tables to choose its cell
    if (std::find(wanted.begin(), wanted.end(), c) != wanted.end()) continue;  // the loader fetches it
    city_.cellBlobs(c, nullptr, 0, scratch);
    for (const uint32_t b : scratch) planned += remote_->blobInfo(b).size;
    if (planned > budget) break;
    if (remote_->fetchBlobs(scratch.data(), scratch.size(), err, true) != core::Status::Ok) break;  // the link: later
    cached_ahead_m_.store(measureAhead(cells, road, scratch), std::memory_order_relaxed);
  }
  cached_ahead_m_.store(measureAhead(cells, road, scratch), std::memory_order_relaxed);
}

void LinkPrefetch::run() {
  std::vector<uint32_t> cells, wanted, scratch, terrain;
  terrain.reserve(kMaxTerrain);
  size_t road = 0;
  uint64_t seen = ~0ull;
  std::string err;
  auto last_request = std::chrono::steady_clock::now();
  uint64_t last_requests = 0;
  for (;;) {
    uint64_t id = 0;
    {
      std::unique_lock<std::mutex> lock(mu_);
      cv_.wait_for(lock, std::chrono::milliseconds(500),
                   [&] { return stop_ || plan_id_ != seen || terrain_new_ || remote_->tablesWanted(); });
      if (stop_) return;
      terrain.assign(terrain_.begin(), terrain_.end());  // asked for again at each wake until cached
      terrain_new_ = false;
      cells = next_;
      wanted = wanted_;
      road = road_n_;
      seen = id = plan_id_;
    }
    // Table pages a frame read and did not wait for first: the frames after it wait for them.
    for (uint64_t offset, size; remote_->takeWantedTables(&offset, &size);)
      if (remote_->ensureTables(offset, size, err) != core::Status::Ok) {
        remote_->clearWantedTables();  // the link failed: the frames ask again
        break;
      }
    // The terrain a frame wanted: small, and in view now.
    if (!terrain.empty() && remote_->mode() == remote::LinkMode::Online && !remote_->changed())
      remote_->fetchBlobs(terrain.data(), terrain.size(), err, true);
    try {
      fetchAhead(cells, wanted, road, id, scratch, err);
    } catch (const core::Error&) {
      // A table page the link could not bring (offline, down): later.
    }
    const uint64_t requests = remote_->stats().link.requests;
    const double idle = std::chrono::duration<double>(std::chrono::steady_clock::now() - last_request).count();
    const bool online = remote_->mode() == remote::LinkMode::Online && !remote_->changed();
    if (requests != last_requests) {
      last_requests = requests, last_request = std::chrono::steady_clock::now();
    } else if (online && !remote_->tablesComplete() && idle > kFillTablesIdleS) {
      remote_->fillTables(err, [&] {
        std::lock_guard<std::mutex> lock(mu_);
        return stop_ || plan_id_ != id;
      });
    } else if (online && idle > kRevalidateS) {
      remote_->revalidate(err);
      last_request = std::chrono::steady_clock::now();
    }
  }
}

}  // namespace blvd::runtime
