// The resident-cell slots: one GL slab each, carved at create, and the state
// machine that fills them (docs/decisions/0006):
//
//   Empty --request--> Loading --staged meshes uploaded, shared blocks copied--> Resident
//     ^                  |                                                         |
//     +--- dropped, load failed                  chosen as Residency's victim -----+
//
// Each frame `stream` asks the loader for what Residency wants, into free or
// releasable slots, then uploads finished staging into its slab and copies the
// blocks a new cell shares with a resident one GPU to GPU (block reuse), all
// within the frame's upload budget. It never waits for a load. Files:
// cell_slots.cpp (requests and eviction), slot_upload.cpp (staging -> slab),
// block_copy.cpp (shared blocks slab -> slab).
#pragma once
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "graph/street_graph.h"
#include "render/renderer.h"
#include "runtime/cell_loader.h"
#include "runtime/memory_plan.h"
#include "stream/city.h"
#include "stream/residency.h"

namespace blvd::runtime {

// A slab upload or copy moves at most this much a step.
inline constexpr uint64_t kUploadChunk = 128 << 10;

// Milliseconds from t0 to now.
double msSince(std::chrono::steady_clock::time_point t0);

// One local block in a slot: its levels of detail, finest first.
struct SlotBlock {
  uint32_t block = 0;
  uint32_t levels = 0;
  render::MeshHandle lod[graph::kMaxBlockLods];
  // Set when the slot is resident, so a frame reads no table: the cell's
  // coverage hint for the block (Marvie's budget share) and its record
  // (bounds, level counts and errors).
  float ach = 0.f;
  graph::BlockRecord record{};
};

// A local block another resident slot holds, to be copied from it.
struct BlockCopy {
  uint32_t block = 0;
  uint32_t from = 0;  // slot index
};

struct CellSlot {
  enum State { Empty, Loading, Resident } state = Empty;
  uint32_t cell = graph::kNone;
  render::SlabHandle slab;
  std::vector<SlotBlock> blocks;                   // reserved once
  std::vector<render::MeshHandle> layered, single;  // impostor layers, in the package's order
  std::vector<stream::LayerInfo> layers;  // the cell's layers, layered then single (reserved once)
  uint32_t layered_count = 0, single_count = 0;
  uint64_t bytes = 0;  // slab bytes in use
  // Loading: the staged (decoded) meshes are all in, and the blocks shared
  // with other slots are copied after them, in order, a level at a time.
  bool staged = false;
  std::vector<BlockCopy> copies;  // reserved once
  uint32_t copies_done = 0, copy_level = 0;
  bool copy_open = false;  // the SlotBlock of copies[copies_done] is pushed
  uint32_t copy_refs = 0;  // other slots' pending copies from this one: not released meanwhile
};

// What the slots count, for blvd_stats.
struct SlotCounters {
  uint64_t load_errors = 0, evictions = 0, blocks_reused = 0, block_levels_copied = 0;
  uint64_t link_waits = 0;  // loads whose data was not available (offline, link down)
  double upload_ms = 0, upload_ms_max = 0;
};

class CellSlots {
 public:
  // Carves plan.resident_cells slabs. `block_reuse` false: every block is
  // decoded, never copied. Throws core::Error(Backend) when a slab cannot be made.
  CellSlots(const stream::City& city, render::Renderer& renderer, CellLoader& loader, const MemoryPlan& plan,
            bool block_reuse);
  // Releases the slabs; the GL context must be current.
  void releaseAll();

  // One frame's residency for the current `cell` (kNone: none): requests,
  // then uploads and copies within `upload_budget_ms`.
  void stream(stream::Residency& residency, uint32_t cell, double arc_m, double speed_mps, double upload_budget_ms);
  const CellSlot* resident(uint32_t cell) const;
  // Whether the cell's load failed (it is not asked for again; lastError() says why).
  bool failed(uint32_t cell) const {
    return cell != graph::kNone && std::find(failed_cells_.begin(), failed_cells_.end(), cell) != failed_cells_.end();
  }

  uint32_t residentCount() const;
  uint64_t usedBytes() const;
  uint64_t highWaterBytes() const { return high_water_; }
  const SlotCounters& counters() const { return counters_; }
  // Why the last load failed (a cell's decode error, or a slab that was too small).
  const std::string& lastError() const { return last_error_; }

 private:
  void request(stream::Residency& residency, uint32_t cell);
  void empty(size_t i);
  // A package on a server (link_slots.cpp): whether the r-th wanted cell may
  // be asked for now (not waiting after an unavailable load; offline, or
  // metered past the next cell, only when its blobs are all cached); the
  // wanted cells' blobs pinned in the disk cache; an unavailable load.
  bool mayFetch(uint32_t cell, uint32_t r);
  void pinWanted(const stream::Residency& residency);
  void waitForLink(uint32_t cell);
  // slot_upload.cpp
  void uploadStaged(double budget_ms);
  bool uploadMeshes(CellSlot& slot, Staging& st, std::chrono::steady_clock::time_point t0, double budget_ms,
                    double& spent);
  void finishSlot(CellSlot& slot);
  // block_copy.cpp
  uint32_t sharedBlocks(uint32_t cell, uint32_t victim, std::vector<BlockCopy>& copies, uint32_t* skip) const;
  void copySharedBlocks(std::chrono::steady_clock::time_point t0, double budget_ms, double& spent);
  bool copyLevels(CellSlot& slot, const SlotBlock* src, std::chrono::steady_clock::time_point t0, double budget_ms,
                  double& spent);
  void dropCopies(CellSlot& slot);

  const stream::City& city_;
  render::Renderer& renderer_;
  CellLoader& loader_;
  const MemoryPlan& plan_;
  bool block_reuse_ = true;
  std::vector<CellSlot> slots_;
  std::vector<uint32_t> slot_cells_;      // slots_[i].cell, for Residency::victim
  std::unique_ptr<bool[]> copy_sources_;  // per slot: blocks are copied from it (kept by Residency::victim)
  std::vector<BlockCopy> copy_scratch_;   // a request's shared blocks, before it is accepted
  uint32_t skip_scratch_[kMaxSkippedBlocks] = {};
  std::vector<uint32_t> failed_cells_;  // cells whose load failed, not retried (fixed ring)
  size_t failed_next_ = 0;
  struct LinkWait {
    uint32_t cell = graph::kNone;
    std::chrono::steady_clock::time_point until{};
  };
  LinkWait link_waits_[8];  // cells whose data was unavailable: not asked for again before `until`
  size_t link_wait_next_ = 0;
  std::vector<uint32_t> pinned_cells_, blob_scratch_, pin_scratch_;  // a package on a server only
  render::SlabUpload pending_upload_;  // the mesh being copied into its slab, chunk by chunk
  render::SlabUpload pending_copy_;    // the shared block level being copied GPU-side
  uint64_t high_water_ = 0;
  SlotCounters counters_;
  std::string last_error_;
};

}  // namespace blvd::runtime
