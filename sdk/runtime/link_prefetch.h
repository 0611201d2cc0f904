// Prefetch planned by the link, for a package on a server: the blobs of the
// cells ahead along the route (without one: every way ahead, breadth first;
// straight on is the road cachedAheadM() measures) are fetched into the disk cache, further than
// the cell slots reach, so that the drive rides through a tunnel and the
// slots' loads find their data on disk (Marvie et al. §4: prefetch the cells
// ahead, release the furthest; the disk cache's LRU releases).
//
// How far: horizon_s = kOutageS + 2 × (a cell's bytes / the measured
// throughput), at the vehicle's speed, at least kMinAheadM; at most half the
// blob cache's bytes, so the prefetch never evicts what it fetched. A slow
// link thus looks further ahead: each cell takes longer to arrive.
//
// The terrain tiles a frame wanted and the cache lacks are fetched first.
//
// Threads: plan() and wantTerrain() on the render thread, when the cell changes and every 32
// frames (a mutex for a copy of a few hundred ids, no allocation after the
// first frames); the fetching on a thread of its
// own, which yields the link to the loader's requests (RemotePackage's
// foreground first). Online only: metered and offline fetch nothing here.
// For a package whose tables arrive a page at a time it reads, for each cell
// ahead, what a frame there reads to choose its cell (City::warmCell), so the
// link brings those pages first. It also fetches the table pages a frame found missing (a frame never
// waits for the link: RemotePackage::ensureTables without waiting), first.
// Online with nothing fetched for kFillTablesIdleS, it completes the table
// mirror of a package whose tables arrive a page at a time (what the first
// frames did not read: RemotePackage::fillTables), so that a drive on without
// the link has its map; with nothing fetched for kRevalidateS, it asks the
// server whether the package is still the same one (RemotePackage::revalidate).
#pragma once
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

#include "stream/city.h"
#include "stream/residency.h"

namespace blvd::runtime {

class LinkPrefetch {
 public:
  static constexpr double kOutageS = 30.0;    // a tunnel's worth of road cached ahead
  static constexpr double kMinAheadM = 400.0; // with no speed known (host-set poses)
  static constexpr size_t kMaxCells = 512;
  static constexpr double kRevalidateS = 60.0;  // online with nothing to fetch: is the package still this one?
  static constexpr double kFillTablesIdleS = 5.0;  // online with nothing to fetch: the rest of the tables
  static constexpr size_t kMaxTerrain = 64;

  explicit LinkPrefetch(const stream::City& city);  // a thread only for a package on a server
  ~LinkPrefetch();
  LinkPrefetch(const LinkPrefetch&) = delete;
  LinkPrefetch& operator=(const LinkPrefetch&) = delete;

  // Render thread, every frame: the current cell, the route ahead of it
  // (residency's route, else its wanted cells) and the speed.
  void plan(uint32_t cell, const stream::Residency& residency, double speed_mps);
  // Render thread, every frame: the terrain tiles' blobs the frame wanted and
  // the cache lacks (TerrainSet::uncachedBlobs), fetched before the road
  // ahead (a few kilobytes each, and what the view shows now), at each of
  // its wakes until the frames stop asking. At most kMaxTerrain are kept.
  void wantTerrain(const std::vector<uint32_t>& blobs);
  // Metres of road ahead, the current cell's rest included, whose cells are
  // all cached (measured by the thread after each cell; 0 for a local package).
  double cachedAheadM() const { return cached_ahead_m_.load(std::memory_order_relaxed); }
  double horizonM() const { return horizon_m_.load(std::memory_order_relaxed); }

 private:
  void run();
  void planFrom(uint32_t cell, const stream::Residency& residency, double speed_mps);
  void fetchAhead(const std::vector<uint32_t>& cells, const std::vector<uint32_t>& wanted, size_t road, uint64_t id,
                  std::vector<uint32_t>& scratch, std::string& err);
  void addWaysAhead(uint32_t cell, double horizon);
  // Metres of cells[0 .. road) cached in a row from the first.
  double measureAhead(const std::vector<uint32_t>& cells, size_t road, std::vector<uint32_t>& scratch) const;

  const stream::City& city_;
  remote::RemotePackage* remote_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::vector<uint32_t> next_;    // the newest plan: the road ahead, in order (under mu_)
  std::vector<uint32_t> wanted_;  // its cells the slots load themselves: not fetched here (under mu_)
  size_t road_n_ = 0;             // next_[0 .. road_n_) is the road ahead, the rest other turns (under mu_)
  std::vector<uint32_t> terrain_;  // terrain blobs wanted (under mu_)
  bool terrain_new_ = false;       // terrain_ changed since the thread copied it (under mu_)
  uint64_t plan_id_ = 0;        // bumped when the plan's first cell changes
  std::vector<uint32_t> walk_;  // plan() scratch, render thread
  std::vector<std::pair<uint32_t, double>> ways_;  // addWaysAhead's queue: cell, metres to its start
  uint32_t planned_cell_ = graph::kNone;
  uint32_t frames_since_plan_ = 0;
  double avg_cell_bytes_ = 0;   // render thread
  bool stop_ = false;
  std::atomic<double> cached_ahead_m_{0}, horizon_m_{0};
  std::thread thread_;
};

}  // namespace blvd::runtime
