// The loader thread ("Streaming"): reads a cell's blobs from the
// mapped package, decodes GLB/Draco and images, and writes the renderer's GPU
// layout into one of kStagingSlots fixed arenas. The render thread then copies
// a ready slot into a GL slab within its upload budget and hands it back.
//
// Memory: the arenas and their mesh tables are carved at construction through
// the host allocator. The decoder's scratch (a MeshData reused for every mesh)
// grows on this thread only, is capped by the largest mesh the package
// declares, and its high-water mark is reported.
// Threads: request()/ready()/release() on the render thread; they take a
// mutex for a few instructions and never allocate. keepOffCpu() moves the
// prediction thread off the render thread's CPU (decision 0008 §12).
#pragma once
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>

#include <sched.h>

#include "blvd/blvd.h"
#include "render/prepared_mesh.h"
#include "runtime/impostor_atlas.h"
#include "stream/city.h"

namespace blvd::runtime {

inline constexpr uint32_t kStagingSlots = 2;
// Blocks a request may name as not to be decoded (the runtime copies them
// from another resident cell); a cell with more shared blocks decodes the rest.
inline constexpr uint32_t kMaxSkippedBlocks = 64;

enum class MeshKind : uint32_t { Block = 0, Layered = 1, Single = 2 };

struct StagedMesh {
  render::PreparedMesh mesh;
  MeshKind kind = MeshKind::Block;
  uint32_t item = 0;   // block id, or layer index within its list
  uint32_t level = 0;  // blocks: level of detail (0 = full)
};

struct Allocator {
  void* (*alloc)(size_t size, size_t align, void* user) = nullptr;
  void (*free)(void* ptr, void* user) = nullptr;
  void* user = nullptr;
  void* allocate(size_t size) const;
  void release(void* p) const;
};

struct Staging {
  enum State : uint32_t { Free, Queued, Decoding, Ready, Failed };
  State state = Free;
  uint32_t cell = 0xffffffffu;
  uint32_t target = 0;  // the caller's tag (its GPU slot)
  render::StagingArena arena;
  StagedMesh* meshes = nullptr;
  uint32_t mesh_count = 0, mesh_capacity = 0;
  uint32_t uploaded = 0;  // render thread: meshes already copied to the slab
  uint64_t accounted = 0; // arena bytes counted in the pool's used bytes (CellLoader::account)
  bool urgent = false;    // the current cell: decoded at normal priority
  uint32_t skip[kMaxSkippedBlocks] = {};  // local blocks not to decode (copied by the runtime)
  uint32_t skip_count = 0;
  // Set when the cell became current while a background thread decodes it:
  // an urgent copy of the request takes over and this one stops at its next
  // mesh (a SCHED_IDLE thread may not run again soon on a busy CPU).
  std::atomic<bool> abandon{false};
  char error[256] = {0};
  bool unavailable = false;  // Failed because the data is not here now (offline, link down): ask again later
  bool out_of_memory = false;  // Failed for an allocation: counted and reported, but asked for again
  uint32_t bad_blocks = 0;   // Ready without these blocks: their blobs failed the checksum or a read (`error` names the first)
  std::vector<uint32_t> blob_ids;  // a package on a server: the cell's blobs, fetched before decoding
  geo::MeshData scratch;  // the decoder's reusable buffers (one per slot: jobs may run at once)
  stream::City::BlockBlob blob;       // the block being decoded; its bytes kept between cells
  std::vector<uint8_t> impostor_bytes;  // an impostor's blob, likewise
  std::vector<stream::LayerInfo> layers;  // the cell's impostor layers, sized at create
  ImpostorAtlas atlas;                    // their images' places in the slot's atlas, likewise
};

class CellLoader {
 public:
  // Carves kStagingSlots arenas of `arena_bytes` with tables of `meshes`
  // entries and starts the thread. Throws core::Error(NoMem) when the
  // allocator fails (nothing is leaked).
  // With `executor.submit` set, no thread is started: each request becomes a
  // task handed to the host.
  // `low_prefetch`: predictions at nice 19 instead of SCHED_IDLE
  // (BLVD_PREFETCH_LOW).
  // `pace_to_frames`: the background thread starts each mesh in a gap
  // between the process's frames (FrameClocks, decision 0008 §11).
  // `cpu_mask` (blvd_runtime_desc.prefetch_cpu_mask): non-zero pins the
  // background thread to those CPUs (within the constructing thread's;
  // core::Error(InvalidArg) when none is left) and turns keepOffCpu() off.
  // `share` (blvd_runtime_desc.prefetch_share): the background thread's
  // meshes wait in the process-wide prefetch_share bucket (0: no bound).
  CellLoader(const stream::City& city, const Allocator& alloc, uint64_t arena_bytes, uint32_t meshes,
             const blvd_executor& executor = blvd_executor{}, bool low_prefetch = false, bool pace_to_frames = false,
             uint64_t cpu_mask = 0, double share = 0);
  ~CellLoader();
  CellLoader(const CellLoader&) = delete;

  // The slots' impostor atlas as the memory plan carved it (before any
  // request): its width and format. An ETC2 atlas gets each image's ETC2
  // levels encoded with it (the arena must hold them: cellNeed counts them).
  // Without a call: the header's width, RGBA8.
  void setAtlas(int width, render::AtlasFormat format) { atlas_width_ = width, atlas_format_ = format; }
  CellLoader& operator=(const CellLoader&) = delete;

  // Queues `cell` into a free staging slot, tagged `target`. False when every
  // slot is busy.
  // `urgent` (the cell the vehicle is in) is decoded by the normal-priority
  // thread; predictions by the background one (SCHED_IDLE: it runs only on a
  // core nothing else wants, or nice 19 where the policy is refused or
  // low_prefetch is set), so
  // that they delay themselves, not the frames (a CPU renderer such as
  // llvmpipe shares the cores with them). See promote() for a prediction
  // that becomes urgent mid-decode.
  // `skip[0..skip_count)` (at most kMaxSkippedBlocks) are local blocks of
  // the cell the caller has already: they are not decoded.
  bool request(uint32_t cell, uint32_t target, bool urgent = false, const uint32_t* skip = nullptr,
               uint32_t skip_count = 0);
  // A slot in state Ready or Failed, oldest request first, or nullptr.
  Staging* finished();
  // Gives a Ready/Failed slot back.
  void release(Staging* s);
  // True when `cell` is queued, decoding or waiting for upload.
  bool pending(uint32_t cell) const;
  // True while a background (prediction) job decodes `cell`.
  bool decodingInBackground(uint32_t cell) const;
  // A prediction that became the current cell: a queued request for `cell`
  // goes to the normal-priority thread; one the background thread is already
  // decoding is requested again as urgent, into a free staging slot (when
  // there is one: the runtime calls this every frame until the cell is
  // resident), and the background copy stops at its next mesh. Whichever
  // copy finishes first is uploaded; the other is dropped by the runtime.
  void promote(uint32_t cell);
  // Drops queued (not yet started) requests.
  void cancelQueued();
  // Render thread, every frame: the CPU it runs on now (sched_getcpu()). The
  // prediction thread is kept off that CPU, within the CPUs it was allowed at
  // construction (decision 0008 §12): a runnable prediction on the render
  // thread's CPU keeps that CPU from going idle when the render thread waits
  // for the GPU or the rasterizer threads, and only an idle CPU pulls a thread
  // that waits on the other one's run queue. A syscall only when the CPU
  // changes; nothing when only one CPU is allowed or with a host executor.
  void keepOffCpu(int cpu);
  // The CPU the prediction thread is kept off now, or -1 (not applied).
  int keptOffCpu() const { return kept_off_; }

  uint64_t loads() const { return loads_; }
  // Arena bytes held now by every slot together (decoding, ready or failed
  // and not yet released), and the most they ever held together.
  uint64_t stagingUsed() const { return staging_used_; }
  uint64_t decodeHighWater() const { return decode_high_water_; }
  uint64_t stagingHighWater() const { return staging_high_water_; }
  uint64_t carvedBytes() const { return carved_; }
  // Background meshes that waited for a gap between frames, and how long.
  uint64_t gapWaits() const { return gap_waits_; }
  double gapWaitMs() const { return double(gap_wait_ns_) * 1e-6; }
  // Background meshes held back by the share, and how long.
  uint64_t shareWaits() const { return share_waits_; }
  double shareWaitMs() const { return double(share_wait_ns_) * 1e-6; }
  // CPU milliseconds spent decoding so far, by the current cell's thread
  // (background false) or the prediction thread: the threads' own CPU clocks
  // (any thread may read them, to the scheduler's tick), or with a host
  // executor the sum of its tasks' meshes.
  double cpuMs(bool background) const;

 private:
  // Stops and joins the threads (after the host's tasks) and gives the arenas back.
  void shutdown();
  void run(bool background);
  // False when the job was abandoned (its slot is then free again).
  bool decode(Staging& s);
  bool decodeCell(Staging& s);  // decode() without its catch
  // What a stage of decodeCell left: go on, the slot is final (Ready or
  // Failed: decodeCell returns true), or the job was abandoned (false).
  enum class Step { Next, Done, Abandoned };
  Step decodeBlocks(Staging& s, std::string& err);
  Step decodeImpostors(Staging& s, std::string& err);
  Step failed(Staging& s, const std::string& what, core::Status st);  // markFailed, then Done
  // The mesh in s.scratch into the slot's arena (an empty one draws nothing);
  // false when that failed the cell.
  bool stageMesh(Staging& s, MeshKind kind, uint32_t item, uint32_t level, std::string& err);
  // An urgent copy took over (promote): true, and the slot is free again.
  bool abandoned(Staging& s);
  void giveBack(Staging& s);  // under mu_
  bool markFailed(Staging& s, const std::string& what, core::Status st);  // Failed (unavailable when the link's)
  bool placeImage(Staging& s, render::PreparedMesh& m, uint32_t layer);
  // Background jobs: waits for a gap between frames to fit a unit of `units`
  // (block: triangles + vertices; impostor: texels + triangles + vertices)
  // at the rate measured so far for its kind.
  void waitForGap(Staging& s, bool impostor, double units);
  // A mesh took `cpu_ns`: learns its kind's rate and, for a prediction,
  // charges the process's prefetch_share bucket.
  void measured(const Staging& s, bool impostor, double units, int64_t cpu_ns);
  // The pool's used bytes follow each slot's arena: account() after the
  // decoder staged a mesh (and raises the high-water mark), unaccount() when
  // the slot is handed back.
  void account(Staging& s);
  void unaccount(Staging& s);
  // Host-executor path: decodes the oldest queued slot, if any.
  static void runTask(void* self);
  void runOne();

  const stream::City& city_;
  Allocator alloc_;
  int atlas_width_ = 0;  // the slots' impostor atlas (impostorAtlasWidth)
  render::AtlasFormat atlas_format_ = render::AtlasFormat::Rgba8;
  Staging slots_[kStagingSlots];
  uint64_t order_[kStagingSlots] = {};  // request sequence, to finish oldest first
  uint64_t seq_ = 0;
  uint64_t carved_ = 0;
  mutable std::mutex mu_;
  std::condition_variable cv_;
  bool stop_ = false;
  std::thread thread_, background_;  // urgent jobs; predictions
  blvd_executor executor_{};
  bool low_prefetch_ = false;
  bool pace_to_frames_ = false;
  double share_ = 0;  // of the wall time, for the process's predictions together (0: no bound)
  // Decode CPU nanoseconds per unit, by kind (0 until measured): written by
  // both decoding threads (measured), read by the background one (waitForGap).
  std::atomic<double> rate_ns_[2] = {};
  std::atomic<uint64_t> gap_waits_{0}, gap_wait_ns_{0}, share_waits_{0}, share_wait_ns_{0};
  std::atomic<uint64_t> task_cpu_ns_[2] = {};  // host executor: its meshes' CPU, urgent / prediction
  clockid_t cpu_clock_[2] = {};                 // the threads' CPU clocks (thread_, background_)
  bool has_cpu_clock_[2] = {false, false};
  uint32_t tasks_out_ = 0;  // submitted to the host and not yet run
  cpu_set_t allowed_{};     // the prediction thread's CPUs as inherited at construction
  bool pinned_ = false;     // cpu_mask given: keepOffCpu() does nothing
  int render_cpu_ = -1;     // render thread only: the CPU keepOffCpu() last saw
  int kept_off_ = -1;
  std::atomic<uint64_t> loads_{0};
  std::atomic<uint64_t> decode_high_water_{0}, staging_used_{0}, staging_high_water_{0};
};

}  // namespace blvd::runtime
