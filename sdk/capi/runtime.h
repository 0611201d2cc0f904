// The object behind blvd_runtime*: the city, the GL context and renderer, the
// pose, and the last error. sdk/capi/blvd_capi.cpp maps the C API onto it.
#pragma once
#include <atomic>
#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "blvd/blvd.h"
#include "render/camera.h"
#include "render/context.h"
#include "render/renderer.h"
#include "capi/cell_loader.h"
#include "capi/frame_clock.h"
#include "capi/memory_plan.h"
#include "stream/frame_budget.h"
#include "stream/residency.h"
#include "stream/city.h"
#include "track/tracker.h"

namespace blvd::capi {

class Runtime {
 public:
  // `desc` has its defaults applied. Throws core::Error naming what failed
  // (Budget when the memory plan exceeds a budget, NoMem when the host
  // allocator fails).
  explicit Runtime(const blvd_runtime_desc& desc);
  ~Runtime();

  void setPoseLocal(double x, double y, double heading_deg, double pitch_deg);
  void setPoseGeo(double lat, double lon, double heading_deg, double pitch_deg);
  // One frame of the current pose: the whole frame, or `n` views of it.
  void render(blvd_frame_stats* stats, const blvd_view* views = nullptr, uint32_t n = 0);
  void readPixels(void* rgba, size_t bytes);
  // The last frame's draw list again as an object-id buffer (blvd_read_items).
  void readItems(uint32_t* ids, size_t count);
  void info(blvd_runtime_info* out) const;
  void setMode(blvd_render_mode mode, float radius_m);
  void setRoute(const uint32_t* cells, size_t n);
  void waitResident(double timeout_ms);
  void stats(blvd_stats* out) const;

  // Tracking. The feeds are safe from any thread and never touch last_error
  // (another thread may be reading it); getPose runs on the render thread.
  blvd_status feedGnss(const blvd_gnss_fix& fix);
  blvd_status feedOdometry(const blvd_odometry& odo);
  void getPose(double t, blvd_pose* out);
  void getCalibration(blvd_odometry_calibration* out) const;
  void setCalibration(const blvd_odometry_calibration& in);
  void setStartPose(const blvd_start_pose& in);

  std::string last_error;

 private:
  // One resident-cell slot: a GL slab and the handles of what was placed in
  // it (local blocks, layered and single impostors), in vectors reserved once.
  struct SlotBlock {
    uint32_t block = 0;
    uint32_t levels = 0;
    render::MeshHandle lod[graph::kMaxBlockLods];
  };
  // A local block another resident slot holds, to be copied from it.
  struct BlockCopy {
    uint32_t block = 0;
    uint32_t from = 0;  // slots_ index
  };
  struct CellSlot {
    enum State { Empty, Loading, Resident } state = Empty;
    uint32_t cell = 0xffffffffu;
    render::SlabHandle slab;
    std::vector<SlotBlock> blocks;
    std::vector<render::MeshHandle> layered, single;
    uint64_t bytes = 0;  // slab bytes in use
    // Loading: the staged (decoded) meshes are all in, and the blocks shared
    // with other slots are copied after them, in order, a level at a time.
    bool staged = false;
    std::vector<BlockCopy> copies;  // reserved once
    uint32_t copies_done = 0, copy_level = 0;
    bool copy_open = false;  // the SlotBlock of copies[copies_done] is pushed
    uint32_t copy_refs = 0;  // other slots' pending copies from this one: not released meanwhile
  };
  // The camera from the tracker when it drives, then the current cell.
  uint32_t currentCell(double& arc_m, double& speed_mps);
  // A pose set by the host: the cell the last frame had while the pose still
  // lies along it, else the next on the route or a successor, when these
  // cost within kStickM of the nearest cell (`cell`, `cost`); else `cell`.
  uint32_t continuedCell(uint32_t cell, double cost, glm::dvec2 p, double heading_deg, double& arc_m) const;
  // Residency for this frame: requests, then uploads within upload_budget_ms.
  void stream(uint32_t cell, double arc_m, double speed_mps, double upload_budget_ms);
  void uploadStaged(double budget_ms);
  // Copies the shared blocks of Loading slots whose staging is in, within
  // the frame's upload budget (`spent` so far since t0); slots become resident.
  void copySharedBlocks(std::chrono::steady_clock::time_point t0, double budget_ms, double& spent);
  // The blocks of `cell` that another resident slot than `victim` holds
  // whole: into `copies` and their ids into `skip` (at most kMaxSkippedBlocks).
  uint32_t sharedBlocks(uint32_t cell, uint32_t victim, std::vector<BlockCopy>& copies, uint32_t* skip) const;
  // Gives back the copy sources' references of a slot's pending copies.
  void dropCopies(CellSlot& slot);
  void finishSlot(CellSlot& slot);
  void buildDrawList(uint32_t cell, double arc_m);
  static float activeRun(const std::vector<graph::ImpostorLayer>& layers, double arc_m);
  void ensureReferenceBlocks();
  const CellSlot* residentSlot(uint32_t cell) const;
  // Level of detail per block of `slot` into level_: Marvie's budget when a
  // target is set, else the coarsest level within lod_error_px.
  void chooseLevels(const CellSlot& slot);
  float coverage(uint32_t cell, uint32_t block) const;

  blvd_runtime_desc desc_;
  stream::City city_;
  MemoryPlan plan_;
  std::unique_ptr<CellLoader> loader_;
  std::unique_ptr<render::Context> ctx_;
  std::unique_ptr<render::Renderer> renderer_;
  std::unique_ptr<stream::Residency> residency_;
  std::vector<CellSlot> slots_;
  std::vector<uint32_t> slot_cells_;  // slots_[i].cell, for Residency::victim
  std::unique_ptr<bool[]> copy_sources_;  // per slot: blocks are copied from it (kept by Residency::victim)
  std::vector<BlockCopy> copy_scratch_;  // a request's shared blocks, before it is accepted
  uint32_t skip_scratch_[kMaxSkippedBlocks] = {};
  std::vector<uint32_t> failed_cells_;  // cells whose load failed, not retried (fixed ring)
  size_t failed_next_ = 0;

  // FULL and RADIUS are reference modes for benchmarks: they need every
  // block, loaded on first use outside the budget (docs/decisions/0006).
  std::vector<render::MeshHandle> reference_blocks_;
  std::vector<render::MeshHandle> draw_;  // this frame's list, reserved at create
  std::vector<uint32_t> draw_items_;      // its object ids (blvd_read_items), reserved with it
  uint64_t frame_ = 0;
  uint32_t last_cell_ = 0xffffffffu;  // the cell of the last frame with a host-set pose
  FrameClock* clock_ = nullptr;  // this runtime's frames, for the loaders' gap scheduling
  blvd_render_mode mode_ = BLVD_MODE_BLVD;
  float radius_m_ = 250.f;
  uint32_t impostors_drawn_ = 0, blocks_drawn_ = 0;
  uint32_t last_drawn_cell_ = 0xffffffffu;
  bool degraded_ = false;
  render::Camera cam_;
  bool rendered_ = false;
  bool items_drawn_ = false;  // readItems drew over the frame
  blvd_stats stats_{};
  render::SlabUpload pending_upload_;  // the mesh being copied into its slab, chunk by chunk
  render::SlabUpload pending_copy_;    // the shared block level being copied GPU-side
  std::unique_ptr<stream::FrameBudget> budget_;  // with target_frame_ms
  uint64_t floor_tris_ = 0;  // the visible blocks' coarsest levels, last frame
  // chooseLevels scratch, sized for the largest cell at create.
  std::vector<float> ach_;
  std::vector<stream::LodChain> chains_;
  std::vector<uint32_t> order_, visible_;
  std::vector<uint8_t> level_, visible_level_;
  uint64_t block_tris_ = 0;
  uint64_t gpu_high_water_ = 0;
  // The tracker drives the camera once it has a pose, until the host places
  // the camera itself (blvd_set_pose_*); the next feed hands it back.
  std::unique_ptr<track::Tracker> tracker_;
  std::atomic<bool> manual_pose_{true};
  std::atomic<double> last_feed_t_{0.0};
};

}  // namespace blvd::capi
