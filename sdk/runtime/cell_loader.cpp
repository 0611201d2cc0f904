#include "runtime/cell_loader.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>

#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include "render/atlas_etc2.h"
#include "runtime/frame_clock.h"
#include "runtime/prefetch_share.h"
#include "core/status.h"

namespace blvd::runtime {
namespace {
constexpr int kBackgroundNice = 19;
// The longest a background mesh waits for a gap: a bound, so that a host whose
// frames are irregular still gets its predictions (≈ 6 frames at 60 Hz).
constexpr int64_t kMaxGapWaitNs = 100000000;
// Estimates get this margin over the measured rate.
constexpr double kCostMargin = 1.25;

void raiseTo(std::atomic<uint64_t>& mark, uint64_t v) {
  uint64_t seen = mark.load();
  while (v > seen && !mark.compare_exchange_weak(seen, v)) {
  }
}

int64_t threadCpuNs() {
  timespec ts{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return int64_t(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}
}  // namespace

void* Allocator::allocate(size_t size) const {
  if (alloc) return alloc(size, 16, user);
  return std::aligned_alloc(16, (size + 15) & ~size_t(15));
}

void Allocator::release(void* p) const {
  if (!p) return;
  if (free) free(p, user);
  else std::free(p);
}

CellLoader::CellLoader(const stream::City& city, const Allocator& alloc, uint64_t arena_bytes, uint32_t meshes,
                       const blvd_executor& executor, bool low_prefetch, bool pace_to_frames, uint64_t cpu_mask,
                       double share)
    : city_(city),
      alloc_(alloc),
      executor_(executor),
      low_prefetch_(low_prefetch),
      pace_to_frames_(pace_to_frames),
      share_(share > 0 ? share : 0) {
  // The threads inherit the constructing thread's CPUs; keepOffCpu() only
  // ever narrows that set. Checked before anything is carved.
  CPU_ZERO(&allowed_);
  if (::pthread_getaffinity_np(pthread_self(), sizeof allowed_, &allowed_) != 0) CPU_ZERO(&allowed_);
  cpu_set_t pin;
  CPU_ZERO(&pin);
  if (cpu_mask && !executor_.submit) {
    for (int c = 0; c < 64; ++c)
      if ((cpu_mask >> c & 1) && CPU_ISSET(c, &allowed_)) CPU_SET(c, &pin);
    if (CPU_COUNT(&pin) == 0) {
      char hex[32];
      std::snprintf(hex, sizeof hex, "0x%llx", static_cast<unsigned long long>(cpu_mask));
      throw core::Error(core::Status::InvalidArg, std::string("prefetch_cpu_mask ") + hex +
                                                      " names none of the CPUs the creating thread may use");
    }
    pinned_ = true;
  }
  // The heap's part first: a failure here (std::bad_alloc) leaves no host
  // allocation behind.
  for (Staging& s : slots_) s.layers.resize(city_.maxCellLayers()), s.atlas.resize(city_.maxCellLayers());
  atlas_width_ = impostorAtlasWidth(city_.header());
  for (Staging& s : slots_) {
    void* arena = alloc_.allocate(arena_bytes);
    void* table = arena ? alloc_.allocate(sizeof(StagedMesh) * meshes) : nullptr;
    if (!arena || !table) {
      alloc_.release(arena);
      for (Staging& t : slots_) {
        alloc_.release(t.arena.base);
        alloc_.release(t.meshes);
      }
      throw core::Error(core::Status::NoMem, "cannot allocate the loader's staging memory (" +
                                                 std::to_string(arena_bytes) + " bytes per slot)");
    }
    s.arena = {static_cast<uint8_t*>(arena), static_cast<size_t>(arena_bytes), 0};
    s.meshes = new (table) StagedMesh[meshes];
    s.mesh_capacity = meshes;
    carved_ += arena_bytes + sizeof(StagedMesh) * meshes;
  }
  if (!executor_.submit) {
    try {
      thread_ = std::thread([this] { run(false); });
      background_ = std::thread([this] { run(true); });
    } catch (...) {
      // No destructor runs for a constructor that throws: stop the thread
      // that did start and give the arenas back here.
      shutdown();
      throw core::Error(core::Status::NoMem, "out of memory: cannot start the loader's threads");
    }
    if (pinned_) (void)::pthread_setaffinity_np(background_.native_handle(), sizeof pin, &pin);
    has_cpu_clock_[0] = ::pthread_getcpuclockid(thread_.native_handle(), &cpu_clock_[0]) == 0;
    has_cpu_clock_[1] = ::pthread_getcpuclockid(background_.native_handle(), &cpu_clock_[1]) == 0;
  }
}

CellLoader::~CellLoader() { shutdown(); }

void CellLoader::shutdown() {
  {
    std::unique_lock<std::mutex> lock(mu_);
    stop_ = true;
    // Tasks handed to the host still point at this loader: wait for them.
    cv_.wait(lock, [&] { return tasks_out_ == 0; });
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  if (background_.joinable()) background_.join();
  for (Staging& s : slots_) {
    alloc_.release(s.arena.base);
    alloc_.release(s.meshes);  // StagedMesh is trivially destructible
    s.arena.base = nullptr;
    s.meshes = nullptr;
  }
}

bool CellLoader::request(uint32_t cell, uint32_t target, bool urgent, const uint32_t* skip, uint32_t skip_count) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    Staging* free_slot = nullptr;
    for (uint32_t i = 0; i < kStagingSlots; ++i)
      if (slots_[i].state == Staging::Free) {
        free_slot = &slots_[i];
        order_[i] = ++seq_;
        break;
      }
    if (!free_slot) return false;
    free_slot->state = Staging::Queued;
    free_slot->cell = cell;
    free_slot->target = target;
    free_slot->urgent = urgent;
    free_slot->abandon = false;
    free_slot->skip_count = std::min(skip_count, kMaxSkippedBlocks);
    if (skip) std::copy(skip, skip + free_slot->skip_count, free_slot->skip);
    if (executor_.submit) ++tasks_out_;
  }
  if (executor_.submit) executor_.submit(&CellLoader::runTask, this, executor_.user);
  else cv_.notify_all();  // the thread of its kind
  return true;
}

Staging* CellLoader::finished() {
  std::lock_guard<std::mutex> lock(mu_);
  Staging* best = nullptr;
  uint64_t best_seq = ~uint64_t(0);
  for (uint32_t i = 0; i < kStagingSlots; ++i)
    if ((slots_[i].state == Staging::Ready || slots_[i].state == Staging::Failed) && order_[i] < best_seq)
      best = &slots_[i], best_seq = order_[i];
  return best;
}

void CellLoader::release(Staging* s) {
  std::lock_guard<std::mutex> lock(mu_);
  unaccount(*s);
  s->state = Staging::Free;
  s->cell = 0xffffffffu;
  s->uploaded = 0;
}

bool CellLoader::pending(uint32_t cell) const {
  std::lock_guard<std::mutex> lock(mu_);
  for (const Staging& s : slots_)
    if (s.state != Staging::Free && s.cell == cell) return true;
  return false;
}

bool CellLoader::decodingInBackground(uint32_t cell) const {
  std::lock_guard<std::mutex> lock(mu_);
  for (const Staging& s : slots_)
    if (s.state == Staging::Decoding && s.cell == cell && !s.urgent) return true;
  return false;
}

void CellLoader::account(Staging& s) {
  const uint64_t grown = s.arena.used - s.accounted;
  s.accounted = s.arena.used;
  raiseTo(staging_high_water_, staging_used_.fetch_add(grown) + grown);
}

void CellLoader::unaccount(Staging& s) {
  staging_used_.fetch_sub(s.accounted);
  s.accounted = 0;
}

void CellLoader::promote(uint32_t cell) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    Staging* background = nullptr;
    bool urgent_copy = false;
    for (Staging& s : slots_) {
      if (s.cell != cell || s.state == Staging::Free) continue;
      if (s.state == Staging::Queued) s.urgent = true;
      if (s.urgent || s.state == Staging::Ready || s.state == Staging::Failed) urgent_copy = true;
      else if (s.state == Staging::Decoding && !s.abandon) background = &s;
    }
    // A host executor has no background thread: its jobs keep their place.
    if (background && !urgent_copy && !executor_.submit)
      for (uint32_t i = 0; i < kStagingSlots; ++i)
        if (slots_[i].state == Staging::Free) {
          Staging& copy = slots_[i];
          order_[i] = ++seq_;
          copy.state = Staging::Queued;
          copy.cell = cell;
          copy.target = background->target;
          copy.urgent = true;
          copy.abandon = false;
          copy.skip_count = background->skip_count;
          std::copy(background->skip, background->skip + background->skip_count, copy.skip);
          background->abandon = true;
          break;
        }
  }
  cv_.notify_all();
}

void CellLoader::cancelQueued() {
  std::lock_guard<std::mutex> lock(mu_);
  for (Staging& s : slots_)
    if (s.state == Staging::Queued) s.state = Staging::Free, s.cell = 0xffffffffu;
}

void CellLoader::keepOffCpu(int cpu) {
  if (cpu == render_cpu_) return;  // the common case: one compare a frame
  render_cpu_ = cpu;
  if (pinned_ || !background_.joinable() || cpu < 0 || cpu >= CPU_SETSIZE) return;
  cpu_set_t set = allowed_;
  const bool narrow = CPU_ISSET(cpu, &set) && CPU_COUNT(&set) > 1;
  if (narrow) CPU_CLR(cpu, &set);
  if (!narrow && kept_off_ < 0) return;  // nothing to narrow, nothing to undo
  // EINVAL/EPERM (a cpuset changed under the host): predictions simply keep
  // the CPUs they have.
  if (::pthread_setaffinity_np(background_.native_handle(), sizeof set, &set) != 0) {
    kept_off_ = -1;
    return;
  }
  kept_off_ = narrow ? cpu : -1;
}

void CellLoader::runTask(void* self) { static_cast<CellLoader*>(self)->runOne(); }

void CellLoader::runOne() {
  Staging* job = nullptr;
  {
    std::lock_guard<std::mutex> lock(mu_);
    uint64_t best_seq = ~uint64_t(0);
    for (uint32_t i = 0; i < kStagingSlots; ++i)
      if (slots_[i].state == Staging::Queued && order_[i] < best_seq) job = &slots_[i], best_seq = order_[i];
    if (job) job->state = Staging::Decoding;
  }
  // A request cancelled after its task was submitted leaves nothing to do.
  if (job && decode(*job)) ++loads_;
  {
    std::lock_guard<std::mutex> lock(mu_);
    --tasks_out_;
  }
  cv_.notify_all();
}

void CellLoader::run(bool background) {
  if (background) {
    // SCHED_IDLE (sched(7)): the thread runs only on a core that nothing
    // else wants, so a prediction never takes CPU from a frame, however the
    // scheduler places a waking thread. Entering it needs no privilege;
    // leaving it does (hence a thread of its own, and promote()'s urgent
    // copy). Where it is refused, nice 19 (per thread on Linux); failure of
    // both, in a sandbox that forbids them, changes nothing else.
    // BLVD_PREFETCH_LOW asks for nice 19 instead: a share of a saturated CPU.
    // (SCHED_BATCH at nice 19 was measured too: boundary frames 1.18 ms
    // over the others at p50 against 0.44 ms under SCHED_IDLE, decision 0008.)
    const sched_param idle{};
    if (low_prefetch_ || ::pthread_setschedparam(pthread_self(), SCHED_IDLE, &idle) != 0)
      (void)::setpriority(PRIO_PROCESS, static_cast<id_t>(::syscall(SYS_gettid)), kBackgroundNice);
    pthread_setname_np(pthread_self(), "blvd-prefetch");
  } else {
    pthread_setname_np(pthread_self(), "blvd-loader");
  }
  for (;;) {
    Staging* job = nullptr;
    {
      std::unique_lock<std::mutex> lock(mu_);
      auto mine = [&](const Staging& s) { return s.state == Staging::Queued && s.urgent != background; };
      cv_.wait(lock, [&] {
        if (stop_) return true;
        for (Staging& s : slots_)
          if (mine(s)) return true;
        return false;
      });
      if (stop_) return;
      uint64_t best_seq = ~uint64_t(0);
      for (uint32_t i = 0; i < kStagingSlots; ++i)
        if (mine(slots_[i]) && order_[i] < best_seq) job = &slots_[i], best_seq = order_[i];
      job->state = Staging::Decoding;
    }
    if (decode(*job)) ++loads_;
  }
}

void CellLoader::waitForGap(Staging& s, bool impostor, double units) {
  if (s.urgent || executor_.submit) return;
  const int64_t cost = int64_t(rate_ns_[impostor].load(std::memory_order_relaxed) * units * kCostMargin);
  auto cancel = [](void* p) { return static_cast<Staging*>(p)->abandon.load(std::memory_order_relaxed); };
  auto count = [](int64_t waited, std::atomic<uint64_t>& n, std::atomic<uint64_t>& ns) {
    if (waited <= 200000) return;  // not more than the check itself
    n.fetch_add(1, std::memory_order_relaxed);
    ns.fetch_add(uint64_t(waited), std::memory_order_relaxed);
  };
  // The share first: its tokens keep accruing while the gap is waited for,
  // and a mesh then starts at the gap's beginning, not late into it.
  count(prefetch_share::wait(cost, share_, kMaxGapWaitNs, cancel, &s), share_waits_, share_wait_ns_);
  if (pace_to_frames_) count(FrameClocks::waitForGap(cost, kMaxGapWaitNs, cancel, &s), gap_waits_, gap_wait_ns_);
}

double CellLoader::cpuMs(bool background) const {
  const int i = background ? 1 : 0;
  if (has_cpu_clock_[i]) {
    timespec ts{};
    if (::clock_gettime(cpu_clock_[i], &ts) != 0) return 0;
    return double(ts.tv_sec) * 1e3 + double(ts.tv_nsec) * 1e-6;
  }
  return double(task_cpu_ns_[i].load(std::memory_order_relaxed)) * 1e-6;
}

void CellLoader::measured(const Staging& s, bool impostor, double units, int64_t cpu_ns) {
  if (!s.urgent) prefetch_share::charge(cpu_ns, share_);
  if (executor_.submit && cpu_ns > 0) task_cpu_ns_[s.urgent ? 0 : 1].fetch_add(uint64_t(cpu_ns), std::memory_order_relaxed);
  if (units <= 0) return;
  // An exponential average both threads update: compare-and-swap, so neither
  // overwrites the other's sample with a stale average.
  const double r = double(cpu_ns) / units;
  std::atomic<double>& rate = rate_ns_[impostor];
  double old = rate.load(std::memory_order_relaxed);
  while (!rate.compare_exchange_weak(old, old > 0 ? 0.8 * old + 0.2 * r : r, std::memory_order_relaxed)) {
  }
}

// A package on a server reads its tables over the link too: a read that
// cannot (offline, a bad record) throws, and fails the cell as a decode
// error would. So does an allocation that fails: that cell, this time.
bool CellLoader::decode(Staging& s) {
  try {
    return decodeCell(s);
  } catch (const core::Error& e) {
    return markFailed(s, e.what(), e.status());
  } catch (const std::bad_alloc&) {
    return markFailed(s, "out of memory", core::Status::NoMem);
  }
}

bool CellLoader::markFailed(Staging& s, const std::string& what, core::Status st) {
  std::snprintf(s.error, sizeof s.error, "cell %u: %s", s.cell, what.c_str());
  const remote::RemotePackage* r = city_.remote();
  std::lock_guard<std::mutex> lock(mu_);
  s.unavailable = r && (st == core::Status::Unavailable || st == core::Status::Io || st == core::Status::Timeout ||
                        r->changed());
  s.out_of_memory = st == core::Status::NoMem;
  s.state = Staging::Failed;
  return true;
}

// Layer j's decoded image at its place in the slot's atlas. The places were
// packed from the layer table's sizes: an image of another size is corrupt.
bool CellLoader::placeImage(Staging& s, render::PreparedMesh& m, uint32_t j) {
  const stream::LayerInfo& l = s.layers[j];
  if (m.rgba && (m.texture_width != l.texture_width || m.texture_height != l.texture_height)) {
    markFailed(s,
               "impostor layer " + std::to_string(j) + " has a " +
                   std::to_string(m.texture_width) + "x" + std::to_string(m.texture_height) + " image, its table says " +
                   std::to_string(l.texture_width) + "x" + std::to_string(l.texture_height),
               core::Status::Corrupt);
    return false;
  }
  m.atlas_x = s.atlas.x[j];
  m.atlas_y = s.atlas.y[j];
  return true;
}

void CellLoader::giveBack(Staging& s) {
  unaccount(s);
  s.state = Staging::Free;
  s.cell = 0xffffffffu;
  s.abandon = false;
}

CellLoader::Step CellLoader::failed(Staging& s, const std::string& what, core::Status st) {
  markFailed(s, what, st);
  return Step::Done;
}

bool CellLoader::abandoned(Staging& s) {
  if (!s.abandon.load(std::memory_order_relaxed)) return false;
  std::lock_guard<std::mutex> lock(mu_);
  giveBack(s);
  return true;
}

bool CellLoader::stageMesh(Staging& s, MeshKind kind, uint32_t item, uint32_t level, std::string& err) {
  if (s.scratch.empty()) return true;
  if (s.mesh_count >= s.mesh_capacity) return !markFailed(s, "more meshes than the plan's largest cell", core::Status::Corrupt);
  StagedMesh& m = s.meshes[s.mesh_count];
  if (!render::prepareMesh(s.scratch, s.arena, m.mesh, err))
    return !markFailed(s, err, render::outOfMemory(err) ? core::Status::NoMem : core::Status::Corrupt);
  m.kind = kind;
  m.item = item;
  m.level = level;
  ++s.mesh_count;
  account(s);
  const uint64_t scratch_bytes = s.scratch.positions.capacity() * 4 + s.scratch.normals.capacity() * 4 +
                                 s.scratch.colors.capacity() + s.scratch.texcoords.capacity() * 4 +
                                 s.scratch.indices.capacity() * 4 + s.scratch.image.capacity();
  raiseTo(decode_high_water_, scratch_bytes);  // jobs may run at once (two threads, or the host's executor)
  return true;
}

// The cell's local blocks, every level. One open per block: its blob's CRC
// and GLB JSON once for all its levels (decision 0008 §13); the open's cost
// counts with level 0's.
CellLoader::Step CellLoader::decodeBlocks(Staging& s, std::string& err) {
  stream::City::BlockBlob& blob = s.blob;
  for (const uint32_t b : city_.streets().localBlocks(s.cell)) {
    if (std::find(s.skip, s.skip + s.skip_count, b) != s.skip + s.skip_count) continue;  // the runtime copies it
    const graph::BlockRecord rec = city_.block(b);
    for (uint32_t k = 0; k < rec.lod_count; ++k) {
      const double units = double(rec.triangles[k]) + double(rec.vertices[k]);
      waitForGap(s, false, units);
      if (abandoned(s)) return Step::Abandoned;
      const int64_t cpu0 = threadCpuNs();
      if (k == 0) {
        const core::Status st = city_.openBlock(b, blob, err);
        // A bad blob, or one the file no longer holds, costs its block, not the cell.
        if (st == core::Status::Corrupt || (st == core::Status::Io && !city_.remote())) {
          if (s.bad_blocks++ == 0) std::snprintf(s.error, sizeof s.error, "cell %u: block left out: %s", s.cell, err.c_str());
          break;
        }
        if (st != core::Status::Ok) return failed(s, err, st);
      }
      const core::Status st = city_.decodeBlockLevel(blob, k, s.scratch, err);
      if (k + 1 == rec.lod_count) blob.close();
      if (st != core::Status::Ok) return failed(s, err, st);
      if (!stageMesh(s, MeshKind::Block, b, k, err)) return Step::Done;
      measured(s, false, units, threadCpuNs() - cpu0);
    }
  }
  return Step::Next;
}

// The cell's impostor layers (then its single impostors), each image at its
// place in the slot's atlas, encoded to ETC2 there when the slots hold that.
CellLoader::Step CellLoader::decodeImpostors(Staging& s, std::string& err) {
  uint32_t layered = 0, single = 0;
  city_.cellLayers(s.cell, s.layers.data(), static_cast<uint32_t>(s.layers.size()), &layered, &single);
  if (layered + single > 0 &&
      s.atlas.pack(s.layers.data(), layered + single, atlas_width_, render::atlasAlign(atlas_format_)) < 0)
    return failed(s, "an impostor image is wider than the slot's atlas", core::Status::Corrupt);
  for (uint32_t j = 0; j < layered + single; ++j) {
    const stream::LayerInfo& l = s.layers[j];
    const bool in_single = j >= layered;
    const double units = double(l.texture_width) * l.texture_height + l.triangles + l.vertices;
    waitForGap(s, true, units);
    if (abandoned(s)) return Step::Abandoned;
    const int64_t cpu0 = threadCpuNs();
    const core::Status st = city_.decodeImpostorBlob(l.blob, s.scratch, err, &s.impostor_bytes);
    if (st != core::Status::Ok) return failed(s, err, st);
    const uint32_t staged = s.mesh_count;
    if (!stageMesh(s, in_single ? MeshKind::Single : MeshKind::Layered, in_single ? j - layered : j, 0, err))
      return Step::Done;
    if (s.mesh_count > staged) {
      render::PreparedMesh& m = s.meshes[staged].mesh;
      if (!placeImage(s, m, j)) return Step::Done;
      if (m.rgba && atlas_format_ == render::AtlasFormat::Etc2) {
        if (!render::encodeAtlasEtc2(m, s.arena, err)) return failed(s, err, core::Status::Corrupt);
        account(s);
      }
    }
    measured(s, true, units, threadCpuNs() - cpu0);
  }
  return Step::Next;
}

bool CellLoader::decodeCell(Staging& s) {
  s.arena.reset();  // the slot was free: release() / giveBack() uncounted its bytes
  s.mesh_count = 0;
  s.uploaded = 0;
  s.error[0] = 0;
  s.unavailable = false;
  s.out_of_memory = false;
  s.bad_blocks = 0;
  std::string err;
  // A package on a server: the cell's blobs into the disk cache first,
  // neighbours in one request. A link that is down, offline, or a package
  // replaced on the server makes the cell unavailable (asked for again
  // later), not a load error (markFailed).
  if (remote::RemotePackage* r = city_.remote()) {
    city_.cellBlobs(s.cell, s.skip, s.skip_count, s.blob_ids);
    const core::Status st = r->fetchBlobs(s.blob_ids.data(), s.blob_ids.size(), err);
    if (st != core::Status::Ok) return markFailed(s, err, st);
  }
  Step step = decodeBlocks(s, err);
  if (step == Step::Next) step = decodeImpostors(s, err);
  if (step != Step::Next) return step == Step::Done;
  std::lock_guard<std::mutex> lock(mu_);
  // promote() may have started the urgent copy after the last mesh's check:
  // the copy delivers the cell, this one is not a load (both would be
  // counted, and the runtime would discard the second).
  if (s.abandon.load(std::memory_order_relaxed)) {
    giveBack(s);
    return false;
  }
  s.state = Staging::Ready;
  return true;
}

}  // namespace blvd::runtime
