#include "capi/runtime.h"
#include "capi/track_convert.h"

#include <sched.h>

#include <algorithm>
#include <chrono>
#include <thread>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstring>

#include "core/log.h"
#include "render/frustum.h"

namespace blvd::capi {
using core::Error;
using core::Status;

namespace {
// A slab upload or copy moves at most this much a step (uploadStaged, copySharedBlocks).
constexpr uint64_t kUploadChunk = 128 << 10;
}  // namespace

Runtime::Runtime(const blvd_runtime_desc& desc) : desc_(desc) {
  std::string err;
  Status st = city_.open(desc.package_path, err);
  if (st != Status::Ok) throw Error(st, err);

  // The plan first: a budget error must come before anything is allocated.
  plan_ = planMemory(desc, city_);
  const std::string over = budgetError(desc, plan_);
  if (!over.empty()) throw Error(Status::Budget, over);
  Allocator alloc;
  alloc.alloc = desc.allocator.alloc;
  alloc.free = desc.allocator.free;
  alloc.user = desc.allocator.user;
  if (!alloc.alloc != !alloc.free) throw Error(Status::InvalidArg, "allocator needs both alloc and free, or neither");
  loader_ = std::make_unique<CellLoader>(city_, alloc, plan_.staging_arena_bytes, plan_.staging_meshes, desc.executor,
                                         desc.prefetch_priority == BLVD_PREFETCH_LOW,
                                         desc.prefetch_priority == BLVD_PREFETCH_IDLE, desc.prefetch_cpu_mask,
                                         desc.prefetch_share);
  clock_ = FrameClocks::acquire();  // none left: this runtime's frames are not waited for

  ctx_ = render::createContext(static_cast<render::Backend>(desc.backend), err);
  if (!ctx_) throw Error(Status::Backend, err);
  render::RendererDesc rd;
  rd.width = static_cast<int>(desc.width);
  rd.height = static_cast<int>(desc.height);
  // The cell slabs' meshes, plus every block for the reference modes.
  rd.mesh_capacity = plan_.resident_cells * plan_.slab.meshes + static_cast<uint32_t>(city_.blocks().size()) + 1;
  rd.scaled_target = desc.target_frame_ms > 0 && desc.min_render_scale < 1.f;
  renderer_ = render::Renderer::create(*ctx_, rd, err);
  if (!renderer_) throw Error(Status::Backend, err);

  slots_.resize(plan_.resident_cells);
  slot_cells_.assign(plan_.resident_cells, graph::kNone);
  for (CellSlot& slot : slots_) {
    slot.slab = renderer_->createSlab(plan_.slab);
    if (slot.slab.id == 0) throw Error(Status::Backend, "cell slab: " + renderer_->lastError());
    slot.blocks.reserve(plan_.max_local_blocks);
    slot.copies.reserve(std::min<size_t>(plan_.max_local_blocks, kMaxSkippedBlocks));
    slot.layered.reserve(plan_.slab.textures);
    slot.single.reserve(plan_.slab.textures);
  }
  failed_cells_.assign(8, graph::kNone);
  copy_sources_ = std::make_unique<bool[]>(plan_.resident_cells);
  copy_scratch_.reserve(std::min<size_t>(plan_.max_local_blocks, kMaxSkippedBlocks));
  const size_t nb = plan_.max_local_blocks;
  ach_.resize(nb);
  chains_.resize(nb);
  order_.resize(nb);
  visible_.resize(nb);
  level_.resize(nb);
  visible_level_.resize(nb);
  if (desc.target_frame_ms > 0) {
    // The budget never needs to exceed the largest cell's local model at full detail.
    const uint64_t most = std::max<uint64_t>(1, city_.header().max_cell_local_lod0_triangles);
    budget_ = std::make_unique<stream::FrameBudget>(desc.target_frame_ms, most,
                                                    rd.scaled_target ? desc.min_render_scale : 1.0);
  }
  stats_.render_scale = 1.f;
  residency_ = std::make_unique<stream::Residency>(city_.graph(), plan_.resident_cells, desc.route_capacity);
  draw_.reserve(city_.blocks().size() + plan_.slab.meshes + 1);
  draw_items_.reserve(draw_.capacity());
  setMode(desc.mode, desc.radius_m);
  cam_.fov_y_deg = desc.fov_y_deg;
  cam_.far_m = desc.far_m;
  cam_.width = static_cast<int>(desc.width);
  cam_.height = static_cast<int>(desc.height);
  cam_.eye_enu = {0, 0, desc.eye_height_m};
  track::TrackerDesc td;
  td.eye_height_m = desc.eye_height_m;
  td.ring_capacity = desc.ring_capacity;
  tracker_ = std::make_unique<track::Tracker>(city_.frame(), &city_.graph(), td);
  stats_.max_resident_cells = plan_.resident_cells;
  BLVD_LOG_INFO("runtime: %s, %u cell slots of %.1f MiB GPU, %.1f MiB CPU planned, on %s (%s)", desc.package_path,
                plan_.resident_cells, render::slabGpuBytes(plan_.slab) / 1048576.0, plan_.cpu_bytes / 1048576.0,
                ctx_->name(), renderer_->glRenderer());
}

Runtime::~Runtime() {
  loader_.reset();  // joins the loader thread before the city goes
  FrameClocks::release(clock_);
  if (renderer_ && ctx_ && ctx_->makeCurrent()) {
    for (render::MeshHandle h : reference_blocks_) renderer_->release(h);
    for (CellSlot& slot : slots_) renderer_->resetSlab(slot.slab);
  }
  renderer_.reset();
  ctx_.reset();
}

void Runtime::setPoseLocal(double x, double y, double heading_deg, double pitch_deg) {
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(heading_deg) || !std::isfinite(pitch_deg))
    throw Error(Status::InvalidArg, "pose has a non-finite value");
  if (pitch_deg <= -90 || pitch_deg >= 90) throw Error(Status::InvalidArg, "pitch must be within (-90, 90) degrees");
  cam_.eye_enu = {x, y, desc_.eye_height_m};
  cam_.heading_deg = std::fmod(heading_deg, 360.0);
  cam_.pitch_deg = pitch_deg;
  manual_pose_ = true;
}

// The C flags are the tracker's bits, so they pass through unchanged.
static_assert(BLVD_GNSS_HAS_LATLON == track::kGnssHasLatLon && BLVD_GNSS_HAS_HACC == track::kGnssHasHAcc &&
                  BLVD_GNSS_HAS_TRACK == track::kGnssHasTrack && BLVD_GNSS_HAS_HDOP == track::kGnssHasHdop,
              "GNSS flag bits");
static_assert(BLVD_ODO_SPEED == track::kOdoSpeed && BLVD_ODO_YAW_RATE == track::kOdoYawRate &&
                  BLVD_ODO_WHEEL_SPEEDS == track::kOdoWheelSpeeds && BLVD_ODO_GEAR == track::kOdoGear &&
                  BLVD_ODO_HEADING == track::kOdoHeading,
              "odometry flag bits");
static_assert(BLVD_POSE_VALID == track::kPoseValid && BLVD_POSE_MATCHED == track::kPoseMatched &&
                  BLVD_POSE_DEAD_RECKONING == track::kPoseDeadReckoning &&
                  BLVD_POSE_HEADING_VALID == track::kPoseHeadingValid,
              "pose flag bits");

blvd_status Runtime::feedGnss(const blvd_gnss_fix& in) {
  const track::GnssFix f = toTrack(in);
  tracker_->feedGnss(f);
  last_feed_t_ = std::max(last_feed_t_.load(), f.t);
  manual_pose_ = false;
  return BLVD_OK;
}

blvd_status Runtime::feedOdometry(const blvd_odometry& in) {
  const track::Odometry o = toTrack(in);
  tracker_->feedOdometry(o);
  last_feed_t_ = std::max(last_feed_t_.load(), o.t);
  manual_pose_ = false;
  return BLVD_OK;
}

void Runtime::getPose(double t, blvd_pose* out) {
  if (!std::isfinite(t)) throw Error(Status::InvalidArg, "blvd_get_pose: t is not finite");
  toBlvd(tracker_->update(t), city_.frame(), out);
}

namespace {
// Every field of an input struct is needed; a later, longer struct is read up to them.
void needStructSize(const char* fn, uint32_t got, size_t needed) {
  if (got < needed)
    throw Error(Status::InvalidArg, std::string(fn) + ": struct_size " + std::to_string(got) + " is smaller than the " +
                                        std::to_string(needed) + " bytes it needs");
}
}  // namespace

void Runtime::getCalibration(blvd_odometry_calibration* out) const { toBlvd(tracker_->calibration(), out); }

void Runtime::setCalibration(const blvd_odometry_calibration& in) {
  needStructSize("blvd_set_odometry_calibration", in.struct_size,
                 offsetof(blvd_odometry_calibration, yaw_rate_bias_sigma_dps) + sizeof(double));
  if (!tracker_->setCalibration(toTrack(in))) {
    char msg[256];
    std::snprintf(msg, sizeof msg,
                  "blvd_set_odometry_calibration: speed_scale %g +- %g, yaw_rate_bias_dps %g +- %g: the scale must lie "
                  "in [0.5, 2], the bias within 10 deg/s, the sigmas finite and not negative",
                  in.speed_scale, in.speed_scale_sigma, in.yaw_rate_bias_dps, in.yaw_rate_bias_sigma_dps);
    throw Error(Status::InvalidArg, msg);
  }
}

void Runtime::setStartPose(const blvd_start_pose& in) {
  needStructSize("blvd_set_start_pose", in.struct_size, offsetof(blvd_start_pose, heading_sigma_deg) + sizeof(double));
  if (!tracker_->setStartPose(toTrack(in))) {
    char msg[256];
    std::snprintf(msg, sizeof msg,
                  "blvd_set_start_pose: t %g, lat %g, lon %g, heading %g deg, sigma %g m, heading sigma %g deg: every "
                  "field must be finite, lat within 90, lon within 180, the sigmas not negative",
                  in.t, in.lat, in.lon, in.heading_deg, in.sigma_m, in.heading_sigma_deg);
    throw Error(Status::InvalidArg, msg);
  }
  // Tracking drives the camera from here, at the start pose's time until something is fed.
  last_feed_t_ = std::max(last_feed_t_.load(), in.t);
  manual_pose_ = false;
}

void Runtime::setPoseGeo(double lat, double lon, double heading_deg, double pitch_deg) {
  if (!(lat >= -90 && lat <= 90) || !(lon >= -180 && lon <= 180))
    throw Error(Status::InvalidArg, "latitude/longitude out of range");
  const geo::Enu p = city_.frame().forward(lat, lon, 0);
  setPoseLocal(p.e, p.n, heading_deg, pitch_deg);
}

void Runtime::setMode(blvd_render_mode mode, float radius_m) {
  if (mode < BLVD_MODE_BLVD || mode > BLVD_MODE_SINGLE) throw Error(Status::InvalidArg, "unknown render mode");
  if (!(radius_m >= 0 && radius_m < 1e6)) throw Error(Status::InvalidArg, "radius_m out of range");
  if ((mode == BLVD_MODE_BLVD || mode == BLVD_MODE_SINGLE) && !city_.hasImpostors()) {
    if (mode == BLVD_MODE_SINGLE)
      throw Error(Status::Unsupported, "the package has no impostors (baked with --impostor none)");
    mode = BLVD_MODE_FULL;  // the default on a package without impostors
  }
  mode_ = mode;
  radius_m_ = radius_m > 0 ? radius_m : 250.f;
}

void Runtime::setRoute(const uint32_t* cells, size_t n) {
  if (n && !cells) throw Error(Status::InvalidArg, "blvd_set_route: cells is NULL");
  if (!residency_->setRoute(cells, n))
    throw Error(Status::InvalidArg, "route of " + std::to_string(n) + " cells: a cell is out of range or the route "
                                        "exceeds route_capacity (" + std::to_string(desc_.route_capacity) + ")");
}

const Runtime::CellSlot* Runtime::residentSlot(uint32_t cell) const {
  for (const CellSlot& s : slots_)
    if (s.state == CellSlot::Resident && s.cell == cell) return &s;
  return nullptr;
}

// Copies finished staging into its slab, a chunk of at most kUploadChunk
// bytes at a time (a buffer range, or texture rows), until the frame's upload
// budget is spent: a large block or impostor texture spreads over several
// frames instead of stalling one. At least one chunk a frame, so a load
// always ends.
void Runtime::uploadStaged(double budget_ms) {
  const auto t0 = std::chrono::steady_clock::now();
  double spent = 0;
  while (Staging* st = loader_->finished()) {
    CellSlot& slot = slots_[st->target];
    // Evicted while loading, or the second of a promoted request's two copies.
    if (slot.state != CellSlot::Loading || slot.cell != st->cell || slot.staged) {
      pending_upload_ = render::SlabUpload{};
      loader_->release(st);
      continue;
    }
    if (st->state == Staging::Failed) {
      last_error = st->error;
      ++stats_.load_errors;
      failed_cells_[failed_next_++ % failed_cells_.size()] = st->cell;
      dropCopies(slot);
      slot.state = CellSlot::Empty;
      slot.cell = slot_cells_[st->target] = graph::kNone;
      loader_->release(st);
      continue;
    }
    while (st->uploaded < st->mesh_count) {
      const StagedMesh& m = st->meshes[st->uploaded];
      bool finished = true;
      render::MeshHandle h;
      if (pending_upload_.slab || renderer_->beginSlabUpload(slot.slab, m.mesh, pending_upload_))
        h = renderer_->continueSlabUpload(pending_upload_, kUploadChunk, finished);
      spent = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      if (!finished) {
        if (spent >= budget_ms) break;
        continue;
      }
      pending_upload_ = render::SlabUpload{};
      ++st->uploaded;
      if (h.id == 0) {
        // The plan sized the slab for the largest cell: this is a bug.
        last_error = "cell " + std::to_string(st->cell) + ": " + renderer_->lastError();
        ++stats_.load_errors;
        break;
      }
      if (m.kind == MeshKind::Block) {
        // A block's levels arrive together, finest first.
        if (slot.blocks.empty() || slot.blocks.back().block != m.item) slot.blocks.push_back(SlotBlock{m.item, 0, {}});
        SlotBlock& sb = slot.blocks.back();
        if (m.level < graph::kMaxBlockLods) {
          sb.lod[m.level] = h;
          sb.levels = std::max(sb.levels, m.level + 1);
        }
      } else {
        (m.kind == MeshKind::Layered ? slot.layered : slot.single).push_back(h);
      }
      if (spent >= budget_ms) break;
    }
    if (st->uploaded >= st->mesh_count) {
      loader_->release(st);
      slot.staged = true;
      if (slot.copies_done >= slot.copies.size()) finishSlot(slot);
    }
    if (spent >= budget_ms) break;
  }
  if (spent < budget_ms) copySharedBlocks(t0, budget_ms, spent);
  stats_.upload_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  stats_.upload_ms_max = std::max(stats_.upload_ms_max, stats_.upload_ms);
}

void Runtime::finishSlot(CellSlot& slot) {
  // The copied blocks came after the decoded ones: back into the cell's
  // order of local blocks, so that a cell draws (and shares its budget) the
  // same whichever way its blocks arrived. Block ids are unique in a slot.
  if (!slot.copies.empty()) {
    const graph::StreetGraph& g = city_.graph();
    const uint32_t *first = g.local_blocks.begin(slot.cell), *last = g.local_blocks.end(slot.cell);
    std::sort(slot.blocks.begin(), slot.blocks.end(), [&](const SlotBlock& a, const SlotBlock& b) {
      return std::find(first, last, a.block) < std::find(first, last, b.block);
    });
  }
  const render::SlabUsage u = renderer_->slabUsage(slot.slab);
  const uint64_t tex = uint64_t(plan_.slab.texture_width) * plan_.slab.texture_height * 4 * 4 / 3;
  slot.bytes = u.vertex_bytes + u.index_bytes + u.textures * tex;
  slot.state = CellSlot::Resident;
  uint64_t used = 0;
  for (const CellSlot& other : slots_) used += other.bytes;
  gpu_high_water_ = std::max(gpu_high_water_, used);
}

// The blocks a new cell shares with a resident one are copied from it, GPU
// to GPU, after the cell's own (decoded) meshes are in: a level at a time in
// chunks of kUploadChunk, within the frame's upload budget like an upload.
// The copies come after the staged meshes so that each block's levels stay
// together in slot.blocks.
void Runtime::copySharedBlocks(std::chrono::steady_clock::time_point t0, double budget_ms, double& spent) {
  for (CellSlot& slot : slots_) {
    if (slot.state != CellSlot::Loading || !slot.staged || slot.copies_done >= slot.copies.size()) continue;
    if (pending_copy_.slab && pending_copy_.slab != slot.slab.id) continue;  // another slot's copy is open
    while (slot.copies_done < slot.copies.size()) {
      const BlockCopy& c = slot.copies[slot.copies_done];
      const SlotBlock* src = nullptr;
      for (const SlotBlock& sb : slots_[c.from].blocks)
        if (sb.block == c.block) src = &sb;
      if (!slot.copy_open) {
        slot.blocks.push_back(SlotBlock{c.block, src ? src->levels : 0, {}});
        slot.copy_open = true;
      }
      SlotBlock& dst = slot.blocks.back();
      while (src && slot.copy_level < src->levels) {
        const render::MeshHandle from = src->lod[slot.copy_level];
        if (from.id == 0) {  // a level that decoded to nothing
          ++slot.copy_level;
          continue;
        }
        bool finished = true;
        render::MeshHandle h;
        if (pending_copy_.slab || renderer_->beginSlabCopy(slot.slab, from, pending_copy_))
          h = renderer_->continueSlabUpload(pending_copy_, kUploadChunk, finished);
        spent = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        if (!finished) {
          if (spent >= budget_ms) return;
          continue;
        }
        pending_copy_ = render::SlabUpload{};
        if (h.id == 0) {
          // The source is protected (copy_refs) and the slab sized for the
          // largest cell: this is a bug.
          last_error = "cell " + std::to_string(slot.cell) + ": block " + std::to_string(c.block) +
                       " copy: " + renderer_->lastError();
          ++stats_.load_errors;
        } else {
          dst.lod[slot.copy_level] = h;
          ++stats_.block_levels_copied;
        }
        ++slot.copy_level;
        if (spent >= budget_ms) return;
      }
      --slots_[c.from].copy_refs;
      ++stats_.blocks_reused;
      ++slot.copies_done;
      slot.copy_level = 0;
      slot.copy_open = false;
    }
    finishSlot(slot);
  }
}

uint32_t Runtime::sharedBlocks(uint32_t cell, uint32_t victim, std::vector<BlockCopy>& copies, uint32_t* skip) const {
  copies.clear();
  if (desc_.block_reuse < 0) return 0;
  const graph::StreetGraph& g = city_.graph();
  for (const uint32_t* b = g.local_blocks.begin(cell); b != g.local_blocks.end(cell); ++b) {
    if (copies.size() >= copies.capacity()) break;  // reserved for min(max local blocks, kMaxSkippedBlocks): the rest decode
    for (uint32_t i = 0; i < slots_.size(); ++i) {
      if (i == victim || slots_[i].state != CellSlot::Resident) continue;
      bool has = false;
      for (const SlotBlock& sb : slots_[i].blocks) has |= sb.block == *b;
      if (!has) continue;
      skip[copies.size()] = *b;
      copies.push_back(BlockCopy{*b, i});
      break;
    }
  }
  return static_cast<uint32_t>(copies.size());
}

void Runtime::dropCopies(CellSlot& slot) {
  for (uint32_t i = slot.copies_done; i < slot.copies.size(); ++i) --slots_[slot.copies[i].from].copy_refs;
  if (pending_copy_.slab == slot.slab.id) pending_copy_ = render::SlabUpload{};
  slot.copies.clear();
  slot.copies_done = slot.copy_level = 0;
  slot.copy_open = false;
  slot.staged = false;
}

// Residency for this frame: ask for what is wanted, most wanted
// first, into free or releasable slots; never wait for a load.
void Runtime::stream(uint32_t cell, double arc_m, double speed_mps, double upload_budget_ms) {
  residency_->update({cell, arc_m, speed_mps});
  // A slot whose request was dropped goes back to empty (one copying its
  // shared blocks has no request left, and keeps going).
  for (size_t i = 0; i < slots_.size(); ++i)
    if (slots_[i].state == CellSlot::Loading && !slots_[i].staged && !loader_->pending(slots_[i].cell)) {
      dropCopies(slots_[i]);
      slots_[i].state = CellSlot::Empty;
      slots_[i].cell = slot_cells_[i] = graph::kNone;
    }
  // The current cell jumps the queue: queued predictions make way for it, or
  // its own queued prediction moves to the normal-priority thread.
  if (cell != graph::kNone && !residentSlot(cell)) {
    if (loader_->pending(cell)) loader_->promote(cell);
    else loader_->cancelQueued();
  }
  for (uint32_t r = 0; r < residency_->wantedCount(); ++r) {
    const uint32_t c = residency_->wanted()[r];
    bool have = false;
    for (const CellSlot& s : slots_) have |= s.cell == c && s.state != CellSlot::Empty;
    if (have) continue;
    bool failed = false;
    for (uint32_t f : failed_cells_) failed |= f == c;
    if (failed) continue;
    // A slot that shared blocks are being copied from stays.
    for (size_t i = 0; i < slots_.size(); ++i) copy_sources_[i] = slots_[i].copy_refs > 0;
    const uint32_t v = residency_->victim(slot_cells_.data(), slot_cells_.size(), r, copy_sources_.get());
    if (v == graph::kNone) break;
    const uint32_t shared = sharedBlocks(c, v, copy_scratch_, skip_scratch_);
    if (!loader_->request(c, v, c == cell, skip_scratch_, shared)) break;  // both staging arenas busy
    CellSlot& slot = slots_[v];
    if (slot.cell != graph::kNone) ++stats_.evictions;
    dropCopies(slot);
    renderer_->resetSlab(slot.slab);
    slot.blocks.clear();
    slot.layered.clear();
    slot.single.clear();
    slot.bytes = 0;
    slot.state = CellSlot::Loading;
    slot.cell = slot_cells_[v] = c;
    for (const BlockCopy& bc : copy_scratch_) {
      slot.copies.push_back(bc);
      ++slots_[bc.from].copy_refs;
    }
  }
  uploadStaged(upload_budget_ms);
}

void Runtime::ensureReferenceBlocks() {
  if (!reference_blocks_.empty()) return;
  geo::MeshData mesh;
  std::string err;
  reference_blocks_.resize(city_.blocks().size());
  for (uint32_t b = 0; b < city_.blocks().size(); ++b) {
    const Status st = city_.decodeBlock(b, mesh, err);
    if (st != Status::Ok) throw Error(st, err);
    if (mesh.empty()) continue;
    reference_blocks_[b] = renderer_->upload(mesh);
    if (reference_blocks_[b].id == 0)
      throw Error(Status::Internal, "block " + std::to_string(b) + ": " + renderer_->lastError());
  }
}

float Runtime::coverage(uint32_t cell, uint32_t block) const {
  const auto& vis = city_.cellTables().visibility;
  if (cell >= vis.size()) return 0.f;
  const auto& v = vis[cell];
  const auto it = std::lower_bound(v.blocks.begin(), v.blocks.end(), block);
  if (it == v.blocks.end() || *it != block) return 0.f;
  const size_t i = size_t(it - v.blocks.begin());
  return i < v.ach.size() ? v.ach[i] : 0.f;
}

void Runtime::chooseLevels(const CellSlot& slot) {
  const size_t n = slot.blocks.size();
  const glm::dvec3 eye = render::enuToGltf(cam_.eye_enu);
  block_tris_ = 0;
  if (!budget_) {
    // No frame budget: the coarsest level whose simplification error stays
    // within lod_error_px on screen at the block box's nearest point.
    const double focal_px = cam_.height * 0.5 / std::tan(cam_.fov_y_deg * 3.14159265358979323846 / 360.0);
    for (size_t i = 0; i < n; ++i) {
      const graph::BlockRecord& r = city_.blocks()[slot.blocks[i].block];
      const glm::dvec3 lo(r.bbox_min[0], r.bbox_min[1], r.bbox_min[2]), hi(r.bbox_max[0], r.bbox_max[1], r.bbox_max[2]);
      const double dist = std::max(glm::length(glm::max(glm::max(lo - eye, eye - hi), glm::dvec3(0.0))), 1e-3);
      uint8_t level = 0;
      for (uint32_t k = slot.blocks[i].levels; k-- > 1;)
        if (r.error_m[k] * focal_px <= desc_.lod_error_px * dist) {
          level = static_cast<uint8_t>(k);
          break;
        }
      level_[i] = level;
      block_tris_ += r.triangles[level];
    }
    return;
  }
  // Marvie et al.: frustum-cull, renormalise the cell's coverage hints over
  // the visible blocks, and share the polygon budget P_i = ACH_i · P.
  floor_tris_ = 0;
  const render::Frustum frustum = render::Frustum::fromClip(render::viewProjectionRelative(cam_));
  size_t nv = 0;
  for (size_t i = 0; i < n; ++i) {
    const graph::BlockRecord& r = city_.blocks()[slot.blocks[i].block];
    const glm::dvec3 lo(r.bbox_min[0], r.bbox_min[1], r.bbox_min[2]), hi(r.bbox_max[0], r.bbox_max[1], r.bbox_max[2]);
    level_[i] = static_cast<uint8_t>(slot.blocks[i].levels ? slot.blocks[i].levels - 1 : 0);  // culled anyway
    if (!frustum.intersectsBox((lo + hi) * 0.5 - eye, (hi - lo) * 0.5)) continue;
    visible_[nv] = static_cast<uint32_t>(i);
    ach_[nv] = coverage(slot.cell, slot.blocks[i].block);
    chains_[nv] = stream::LodChain{r.triangles, slot.blocks[i].levels};
    ++nv;
    if (slot.blocks[i].levels) floor_tris_ += r.triangles[slot.blocks[i].levels - 1];
  }
  block_tris_ = stream::shareBudget(budget_->polygonBudget(), ach_.data(), chains_.data(), nv, order_.data(),
                                    visible_level_.data());
  for (size_t j = 0; j < nv; ++j) level_[visible_[j]] = visible_level_[j];
}

// The start of the run that holds arc length `arc_m` (the last run starting
// at or before it; the first when the list is empty or arc_m is before all).
float Runtime::activeRun(const std::vector<graph::ImpostorLayer>& layers, double arc_m) {
  float run = layers.empty() ? 0.f : layers.front().run_from_m;
  for (const graph::ImpostorLayer& l : layers)
    if (double(l.run_from_m) <= arc_m) run = l.run_from_m;
  return run;
}

void Runtime::buildDrawList(uint32_t cell, double arc_m) {
  draw_.clear();
  draw_items_.clear();
  impostors_drawn_ = 0;
  degraded_ = false;
  const auto& blocks = city_.blocks();
  auto addBlock = [&](uint32_t b) {
    if (b < reference_blocks_.size() && reference_blocks_[b].id) {
      draw_.push_back(reference_blocks_[b]);
      draw_items_.push_back(b + 1);
    }
  };
  switch (mode_) {
    case BLVD_MODE_FULL:
      for (uint32_t b = 0; b < reference_blocks_.size(); ++b) addBlock(b);
      break;
    case BLVD_MODE_RADIUS: {
      // Visibility radius (the VOP baseline): blocks whose box comes within R.
      const double ex = cam_.eye_enu.x, ez = -cam_.eye_enu.y;
      for (uint32_t b = 0; b < blocks.size(); ++b) {
        const auto& r = blocks[b];
        const double dx = std::max({double(r.bbox_min[0]) - ex, 0.0, ex - double(r.bbox_max[0])});
        const double dz = std::max({double(r.bbox_min[2]) - ez, 0.0, ez - double(r.bbox_max[2])});
        if (dx * dx + dz * dz <= double(radius_m_) * radius_m_) addBlock(b);
      }
      break;
    }
    case BLVD_MODE_LOCAL:
    case BLVD_MODE_BLVD:
    case BLVD_MODE_SINGLE:
    default: {
      if (cell == graph::kNone) break;
      const CellSlot* slot = residentSlot(cell);
      if (!slot) {
        // Not resident yet: never wait; draw the last cell drawn if it still
        // is, and say so.
        degraded_ = true;
        ++stats_.misses;
        slot = residentSlot(last_drawn_cell_);
        if (!slot) break;
      }
      last_drawn_cell_ = slot->cell;
      // Sillion 97 §3.1: the local model as geometry, each block at the
      // level of detail the budget or the error bound gives it ...
      chooseLevels(*slot);
      for (size_t i = 0; i < slot->blocks.size(); ++i) {
        draw_.push_back(slot->blocks[i].lod[level_[i]]);
        draw_items_.push_back(slot->blocks[i].block + 1);
      }
      if (mode_ == BLVD_MODE_LOCAL) break;
      // ... plus the cell's impostors for the rest; the blocks they stand
      // for are never drawn with them (K06 §3.1.2): they are not local. A
      // long or bending cell has a set per run: the viewer's run's.
      const bool single = mode_ == BLVD_MODE_SINGLE;
      const auto& handles = single ? slot->single : slot->layered;
      const auto& ci = city_.cellTables().impostors[slot->cell];
      const auto& layers = single ? ci.single : ci.layered;
      const float run = activeRun(layers, slot->cell == cell ? arc_m : 0.0);
      for (size_t i = 0; i < handles.size() && i < layers.size(); ++i) {
        if (layers[i].run_from_m != run) continue;
        draw_.push_back(handles[i]);
        draw_items_.push_back(BLVD_ITEM_IMPOSTOR | uint32_t(i + 1));
        ++impostors_drawn_;
      }
      break;
    }
  }
  blocks_drawn_ = static_cast<uint32_t>(draw_.size() - impostors_drawn_);
}

uint32_t Runtime::currentCell(double& arc_m, double& speed) {
  uint32_t cell = graph::kNone;
  arc_m = speed = 0;
  if (!manual_pose_) {
    // Tracking drives the camera: the pose at the newest fed time.
    const track::Pose& p = tracker_->update(last_feed_t_.load());
    if (p.flags & track::kPoseValid) {
      cam_.eye_enu = {p.camera.eye_e, p.camera.eye_n, p.camera.eye_u};
      cam_.heading_deg = p.camera.heading_deg;
      cam_.pitch_deg = p.camera.pitch_deg;
      speed = p.speed_mps;
      if (p.flags & track::kPoseMatched) cell = p.cell, arc_m = p.arc_m;
    }
  }
  if (cell == graph::kNone) {
    const glm::dvec2 p(cam_.eye_enu.x, cam_.eye_enu.y);
    double cost = 0;
    cell = city_.nearestCell(p, cam_.heading_deg, &arc_m, &cost);
    if (cell != graph::kNone) cell = continuedCell(cell, cost, p, cam_.heading_deg, arc_m);
    last_cell_ = cell;
  } else {
    last_cell_ = graph::kNone;
  }
  return cell;
}

// At a junction a pose is about as near the cross street's cells as the one
// it drives along, and the nearest cell alone flickers to a neighbour for a
// frame or two: a cell that is not resident (the frame is degraded, and the
// cell is fetched for nothing) and a false boundary. A host-set pose has no
// map matcher to keep it on its street (the tracker's HMM does that for fed
// poses), so the last cell is kept while the pose lies along it, and at its
// end the route's next cell or a successor takes over, each while it costs
// within kStickM of the nearest. A pose moved far away (a jump) goes by the
// nearest cell.
uint32_t Runtime::continuedCell(uint32_t cell, double cost, glm::dvec2 p, double heading_deg, double& arc_m) const {
  constexpr double kStickM = 3.0;
  if (last_cell_ == graph::kNone || last_cell_ >= city_.graph().cellCount() || cell == last_cell_) return cell;
  double arc = 0;
  bool at_end = false;
  if (city_.cellCost(last_cell_, p, heading_deg, &arc, &at_end) <= cost + kStickM && !at_end) {
    arc_m = arc;
    return last_cell_;
  }
  uint32_t pick = graph::kNone;
  double pick_cost = cost + kStickM, pick_arc = 0;
  auto consider = [&](uint32_t c) {
    double a = 0;
    const double k = city_.cellCost(c, p, heading_deg, &a, nullptr);
    if (k <= pick_cost) pick = c, pick_cost = k, pick_arc = a;
  };
  const uint32_t next = residency_->nextOnRoute(last_cell_);
  if (next != graph::kNone) consider(next);
  const graph::StreetGraph& g = city_.graph();
  if (pick == graph::kNone)
    for (const uint32_t* s = g.successors.begin(last_cell_); s != g.successors.end(last_cell_); ++s) consider(*s);
  if (pick == graph::kNone) return cell;
  arc_m = pick_arc;
  return pick;
}

void Runtime::waitResident(double timeout_ms) {
  if (!(timeout_ms >= 0)) throw Error(Status::InvalidArg, "blvd_wait_resident: timeout_ms must be >= 0");
  if (!ctx_->makeCurrent()) throw Error(Status::Misuse, "the GL context cannot be made current on this thread");
  if (mode_ == BLVD_MODE_FULL || mode_ == BLVD_MODE_RADIUS) return ensureReferenceBlocks();
  double arc_m, speed;
  const uint32_t cell = currentCell(arc_m, speed);
  if (cell == graph::kNone) return;
  const auto t0 = std::chrono::steady_clock::now();
  const uint64_t errors = stats_.load_errors;
  for (;;) {
    stream(cell, arc_m, speed, 1e9);  // waiting: no per-frame upload budget
    if (residentSlot(cell)) return;
    if (stats_.load_errors != errors) throw Error(Status::Corrupt, last_error);
    if (std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() > timeout_ms)
      throw Error(Status::Timeout, "cell " + std::to_string(cell) + " not resident after " +
                                       std::to_string(timeout_ms) + " ms");
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

void Runtime::render(blvd_frame_stats* stats, const blvd_view* views, uint32_t n) {
  if (!ctx_->makeCurrent()) throw Error(Status::Misuse, "the GL context cannot be made current on this thread");
  const auto t_frame = std::chrono::steady_clock::now();
  if (clock_) clock_->begin(monoNs(t_frame));
  loader_->keepOffCpu(::sched_getcpu());
  ++frame_;
  double arc_m, speed;
  const uint32_t cell = currentCell(arc_m, speed);
  if (mode_ == BLVD_MODE_FULL || mode_ == BLVD_MODE_RADIUS) ensureReferenceBlocks();
  else stream(cell, arc_m, speed, desc_.upload_budget_ms);
  buildDrawList(cell, arc_m);
  render::FrameStats fs;
  render::RenderOptions ro;
  ro.scale = budget_ ? budget_->scale() : 1.0;
  uint64_t full_pixels = 0;
  if (!views) {
    full_pixels = uint64_t(cam_.width) * uint64_t(cam_.height);
    if (!renderer_->render(cam_, draw_.data(), draw_.size(), &fs, ro))
      throw Error(Status::Internal, "render failed: " + renderer_->lastError());
  } else {
    // One draw list for every view (Yilmaz et al. §3.4); each view only
    // changes the camera.
    const uint32_t W = desc_.width, H = desc_.height;
    for (uint32_t i = 0; i < n; ++i) {
      const blvd_view v = sized(views[i]);
      const uint32_t w = v.width ? v.width : W, h = v.height ? v.height : H;
      if (v.x >= W || v.y >= H || w > W - v.x || h > H - v.y)
        throw Error(Status::InvalidArg, "view " + std::to_string(i) + " lies outside the " + std::to_string(W) + "x" +
                                            std::to_string(H) + " frame");
      if (!std::isfinite(v.yaw_offset_deg) || !std::isfinite(v.pitch_offset_deg) ||
          !std::isfinite(v.eye_offset_right_m) || !(v.fov_y_deg == 0 || (v.fov_y_deg > 1 && v.fov_y_deg < 179)))
        throw Error(Status::InvalidArg, "view " + std::to_string(i) + " has an angle or offset out of range");
      render::Camera c = cam_;
      c.width = int(w);
      c.height = int(h);
      c.viewport_x = int(v.x);
      c.viewport_y = int(H - v.y - h);  // GL counts rows from the bottom
      c.heading_deg = std::fmod(cam_.heading_deg + v.yaw_offset_deg + 720.0, 360.0);
      c.pitch_deg = std::clamp(cam_.pitch_deg + v.pitch_offset_deg, -89.0, 89.0);
      if (v.fov_y_deg > 0) c.fov_y_deg = v.fov_y_deg;
      const double hr = cam_.heading_deg * 3.14159265358979323846 / 180.0;
      c.eye_enu.x += std::cos(hr) * v.eye_offset_right_m;  // right of the heading
      c.eye_enu.y -= std::sin(hr) * v.eye_offset_right_m;
      c.mirror = (v.flags & BLVD_VIEW_MIRROR) != 0;
      render::FrameStats one;
      if (!renderer_->render(c, draw_.data(), draw_.size(), &one, ro))
        throw Error(Status::Internal, "render failed: " + renderer_->lastError());
      full_pixels += uint64_t(w) * h;
      fs.pixels += one.pixels;
      fs.frame_ms += one.frame_ms;
      fs.triangles += one.triangles;
      fs.draw_calls += one.draw_calls;
    }
    renderer_->setReadSize(int(W), int(H));
  }
  rendered_ = true;
  items_drawn_ = false;
  const auto t_drawn = std::chrono::steady_clock::now();
  if (clock_) clock_->end(monoNs(t_drawn));
  if (budget_ && !(mode_ == BLVD_MODE_FULL || mode_ == BLVD_MODE_RADIUS)) {
    // The whole call counts against the target: streaming and uploads too.
    const double ms = std::chrono::duration<double, std::milli>(t_drawn - t_frame).count();
    budget_->next(ms, block_tris_, floor_tris_, fs.pixels, full_pixels);
    stats_.polygon_budget = budget_->polygonBudget();
    stats_.frame_aim_ms = float(budget_->aim());
    stats_.budget_unreachable = budget_->unreachable() ? 1 : 0;
  }
  stats_.render_scale = float(ro.scale);
  stats_.block_triangles = block_tris_;
  ++stats_.frames;
  stats_.frame_ms = fs.frame_ms;
  stats_.triangles = fs.triangles;
  if (stats) {
    const uint32_t size = stats->struct_size ? stats->struct_size : sizeof(blvd_frame_stats);
    blvd_frame_stats s{};
    s.struct_size = size;
    s.frame_ms = fs.frame_ms;
    s.triangles = fs.triangles;
    s.draw_calls = fs.draw_calls;
    s.cell = cell;
    s.impostor_layers = impostors_drawn_;
    s.blocks_drawn = blocks_drawn_;
    s.flags = degraded_ ? BLVD_FRAME_DEGRADED : 0;
    std::memcpy(stats, &s, std::min<size_t>(size, sizeof s));
  }
}

void Runtime::stats(blvd_stats* out) const {
  blvd_stats s = stats_;
  s.struct_size = out->struct_size ? out->struct_size : sizeof s;
  s.resident_cells = 0;
  uint64_t gpu_used = 0;
  for (const CellSlot& slot : slots_) {
    if (slot.state == CellSlot::Resident) ++s.resident_cells;
    gpu_used += slot.bytes;
  }
  s.gpu.capacity_bytes = renderer_->slabBytes();  // what createSlab made, not what the plan said
  s.gpu.used_bytes = gpu_used;
  s.gpu.high_water_bytes = std::max(gpu_high_water_, gpu_used);
  s.staging.capacity_bytes = loader_->carvedBytes();
  s.staging.used_bytes = loader_->stagingUsed();
  s.staging.high_water_bytes = loader_->stagingHighWater();
  s.decode.high_water_bytes = loader_->decodeHighWater();
  s.table_bytes = city_.tableBytes();
  s.tracking_bytes = tracker_->bytes();
  s.loads = loader_->loads();
  s.prefetch_gap_waits = loader_->gapWaits();
  s.prefetch_gap_wait_ms = loader_->gapWaitMs();
  s.prefetch_kept_off_cpu = loader_->keptOffCpu();
  s.prefetch_share_waits = loader_->shareWaits();
  s.prefetch_share_wait_ms = loader_->shareWaitMs();
  s.loader_cpu_ms = loader_->cpuMs(false);
  s.prefetch_cpu_ms = loader_->cpuMs(true);
  std::memcpy(out, &s, std::min<size_t>(s.struct_size, sizeof s));
}

void Runtime::readPixels(void* rgba, size_t bytes) {
  if (!rendered_) throw Error(Status::Misuse, "blvd_read_pixels before blvd_render");
  if (items_drawn_)
    throw Error(Status::Misuse, "blvd_read_pixels after blvd_read_items: the ids replaced the frame; render again");
  const size_t need = static_cast<size_t>(renderer_->lastWidth()) * renderer_->lastHeight() * 4;
  if (bytes < need)
    throw Error(Status::InvalidArg, "pixel buffer holds " + std::to_string(bytes) + " bytes, the frame needs " +
                                        std::to_string(need));
  if (!renderer_->readPixels(static_cast<uint8_t*>(rgba))) throw Error(Status::Internal, renderer_->lastError());
}

void Runtime::readItems(uint32_t* ids, size_t count) {
  if (!rendered_) throw Error(Status::Misuse, "blvd_read_items before blvd_render");
  const size_t need = size_t(cam_.width) * size_t(cam_.height);
  if (count < need)
    throw Error(Status::InvalidArg, "id buffer holds " + std::to_string(count) + " ids, the frame needs " +
                                        std::to_string(need));
  if (!ctx_->makeCurrent()) throw Error(Status::Misuse, "the GL context cannot be made current on this thread");
  render::RenderOptions ro;
  ro.pass = render::Pass::ItemBuffer;
  ro.item_ids = draw_items_.data();
  if (!renderer_->render(cam_, draw_.data(), draw_.size(), nullptr, ro))
    throw Error(Status::Internal, "item buffer failed: " + renderer_->lastError());
  items_drawn_ = true;
  // The RGBA read-back is unpacked in place: 4 bytes a pixel, one id a pixel.
  auto* px = reinterpret_cast<uint8_t*>(ids);
  if (!renderer_->readPixels(px)) throw Error(Status::Internal, renderer_->lastError());
  for (size_t i = 0; i < need; ++i) {
    const uint8_t* p = px + 4 * i;
    ids[i] = p[3] ? uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 : 0u;
  }
}

void Runtime::info(blvd_runtime_info* out) const {
  blvd_runtime_info i{};
  i.struct_size = out->struct_size ? out->struct_size : sizeof i;
  i.backend = ctx_->name();
  i.gl_renderer = renderer_->glRenderer();
  i.gl_version = renderer_->glVersion();
  i.origin_lat = city_.header().origin_lat;
  i.origin_lon = city_.header().origin_lon;
  i.cell_count = city_.header().cell_count;
  i.block_count = city_.header().block_count;
  i.building_count = city_.header().building_count;
  i.triangle_count = city_.header().triangle_count;
  std::memcpy(out, &i, std::min<size_t>(i.struct_size, sizeof i));
}

}  // namespace blvd::capi
