#include "runtime/runtime.h"

#include <chrono>
#include <cstdio>
#include <cmath>
#include <cstring>
#include <thread>

#include "core/log.h"
#include "runtime/package_source.h"

namespace blvd::runtime {
using core::Error;
using core::Status;

namespace {
Allocator hostAllocator(const blvd_runtime_desc& desc) {
  Allocator alloc;
  alloc.alloc = desc.allocator.alloc;
  alloc.free = desc.allocator.free;
  alloc.user = desc.allocator.user;
  if (!alloc.alloc != !alloc.free) throw Error(Status::InvalidArg, "allocator needs both alloc and free, or neither");
  return alloc;
}
}  // namespace

Runtime::Runtime(const blvd_runtime_desc& desc) : desc_(desc) {
  std::string err;
  openCity(city_, desc.package_path, linkDesc(desc), stream::City::Tables::All);

  // The plan first: a budget error must come before anything is allocated.
  plan_ = planMemory(desc, city_);
  const std::string over = budgetError(desc, plan_);
  if (!over.empty()) throw Error(Status::Budget, over);
  loader_ = std::make_unique<CellLoader>(city_, hostAllocator(desc), plan_.staging_arena_bytes, plan_.staging_meshes,
                                         desc.executor, desc.prefetch_priority == BLVD_PREFETCH_LOW,
                                         desc.prefetch_priority == BLVD_PREFETCH_IDLE, desc.prefetch_cpu_mask,
                                         desc.prefetch_share);
  loader_->setAtlas(plan_.slab.atlas_width, plan_.slab.atlas_format);
  clock_ = FrameClocks::acquire();  // none left: this runtime's frames are not waited for

  ctx_ = render::createContext(static_cast<render::Backend>(desc.backend), err);
  if (!ctx_) throw Error(Status::Backend, err);
  render::RendererDesc rd;
  rd.width = static_cast<int>(desc.width);
  rd.height = static_cast<int>(desc.height);
  // The cell slabs' meshes; the reference modes add every block when first chosen.
  rd.mesh_capacity = plan_.resident_cells * plan_.slab.meshes + plan_.terrain.slots + 1;
  rd.scaled_target = desc.target_frame_ms > 0 && desc.min_render_scale < 1.f;
  renderer_ = render::Renderer::create(*ctx_, rd, err);
  if (!renderer_) throw Error(Status::Backend, err);

  slots_ = std::make_unique<CellSlots>(city_, *renderer_, *loader_, plan_, desc.block_reuse >= 0);
  terrain_ = std::make_unique<TerrainSet>(city_, *renderer_, plan_.terrain, desc.lod_error_px);
  terrain_tiles_.resize(plan_.terrain.slots);
  // What the slabs hold as the GL reports it (the plan's own formula where it cannot).
  bool measured = false;
  gpu_capacity_ = renderer_->measuredSlabBytes(measured);
  if (!measured) gpu_capacity_ = renderer_->slabBytes();
  draw_ = std::make_unique<DrawList>(city_, plan_, desc.lod_error_px);
  if (desc.target_frame_ms > 0) {
    // The budget never needs to exceed the largest cell's local model at full detail.
    const uint64_t most = std::max<uint64_t>(1, city_.header().max_cell_local_lod0_triangles);
    budget_ = std::make_unique<stream::FrameBudget>(desc.target_frame_ms, most,
                                                    rd.scaled_target ? desc.min_render_scale : 1.0);
  }
  stats_.render_scale = 1.f;
  residency_ = std::make_unique<stream::Residency>(city_.streets(), plan_.resident_cells, desc.route_capacity);
  choice_ = std::make_unique<CellChoice>(city_, *residency_);
  link_prefetch_ = std::make_unique<LinkPrefetch>(city_);
  setMode(desc.mode, desc.radius_m);
  cam_.fov_y_deg = desc.fov_y_deg;
  cam_.far_m = desc.far_m;
  cam_.width = static_cast<int>(desc.width);
  cam_.height = static_cast<int>(desc.height);
  cam_.eye_enu = {0, 0, desc.eye_height_m};
  track::TrackerDesc td;
  td.eye_height_m = desc.eye_height_m;
  td.ring_capacity = desc.ring_capacity;
  tracker_ = std::make_unique<track::Tracker>(city_.frame(), &city_.streets(), td);
  stats_.max_resident_cells = plan_.resident_cells;
  BLVD_LOG_INFO("runtime: %s, %u cell slots of %.1f MiB GPU, %.1f MiB CPU planned, on %s (%s)", desc.package_path,
                plan_.resident_cells, render::slabGpuBytes(plan_.slab) / 1048576.0, plan_.cpu_bytes / 1048576.0,
                ctx_->name(), renderer_->glRenderer());
}

// What the table caches did over the runtime's life (docs/decisions/0013).
void Runtime::logPageCaches() const {
  auto line = [](const char* what, const stream::PageCacheStats& st) {
    const uint64_t reads = st.hits + st.misses;
    BLVD_LOG_INFO("runtime: %s page cache: %llu reads, %llu misses (%.2f %%)", what, (unsigned long long)reads,
                  (unsigned long long)st.misses, reads ? 100.0 * st.misses / reads : 0.0);
  };
  if (!city_.paged()) return;
  line("graph", city_.graphPageStats());
  line("cell table", city_.cellTablePageStats());
  line("block", city_.blockPageStats());
}

Runtime::~Runtime() {
  link_prefetch_.reset();  // joins the prefetch thread before the city goes
  loader_.reset();  // joins the loader thread before the city goes
  logPageCaches();
  FrameClocks::release(clock_);
  if (renderer_ && ctx_ && ctx_->makeCurrent()) {
    if (draw_) draw_->releaseReferenceBlocks(*renderer_);
    if (slots_) slots_->releaseAll();
  }
  renderer_.reset();
  ctx_.reset();
}

void Runtime::setCameraSource(blvd_camera_source source) {
  if (source != BLVD_CAMERA_HOST && source != BLVD_CAMERA_TRACKED)
    throw Error(Status::InvalidArg, "blvd_set_camera_source: unknown source");
  camera_source_ = source;
}

void Runtime::setPoseLocal(double x, double y, double heading_deg, double pitch_deg) {
  placeCamera(x, y, heading_deg, pitch_deg, nullptr);
}

// The host's pose; `lat_lon` (or null) names it in the off-map error.
void Runtime::placeCamera(double x, double y, double heading_deg, double pitch_deg, const double* lat_lon) {
  if (camera_source_ == BLVD_CAMERA_TRACKED)
    throw Error(Status::Misuse, "blvd_set_pose_*: the camera follows the tracked pose (BLVD_CAMERA_TRACKED); "
                                "blvd_set_camera_source(rt, BLVD_CAMERA_HOST) first");
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(heading_deg) || !std::isfinite(pitch_deg))
    throw Error(Status::InvalidArg, "pose has a non-finite value");
  if (pitch_deg <= -90 || pitch_deg >= 90) throw Error(Status::InvalidArg, "pitch must be within (-90, 90) degrees");
  cam_.eye_enu = {x, y, desc_.eye_height_m};
  cam_.heading_deg = std::fmod(heading_deg, 360.0);
  cam_.pitch_deg = pose_pitch_deg_ = pitch_deg;
  const double out = graph::outsideStreets(city_.streets(), x, y);
  host_off_map_ = !(out <= graph::kMapMarginM);
  if (!host_off_map_) return;
  char where[96];
  if (lat_lon)
    std::snprintf(where, sizeof where, "lat %.6f, lon %.6f", lat_lon[0], lat_lon[1]);
  else
    std::snprintf(where, sizeof where, "x %.1f m, y %.1f m", x, y);
  char far[48];
  std::snprintf(far, sizeof far, out >= 10000 ? "%.0f km" : "%.0f m", out >= 10000 ? out / 1000 : out);
  throw Error(Status::OffMap, std::string("pose off the map: ") + where + " lies " + far +
                                  " outside the package's streets (the margin is " +
                                  std::to_string(int(graph::kMapMarginM)) + " m); frames draw sky and ground");
}

void Runtime::setPoseGeo(double lat, double lon, double heading_deg, double pitch_deg) {
  if (!(lat >= -90 && lat <= 90) || !(lon >= -180 && lon <= 180))
    throw Error(Status::InvalidArg, "latitude/longitude out of range");
  const geo::Enu p = city_.frame().forward(lat, lon, 0);
  const double lat_lon[2] = {lat, lon};
  placeCamera(p.e, p.n, heading_deg, pitch_deg, lat_lon);
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

void Runtime::setLinkMode(blvd_link_mode mode) {
  if (remote::RemotePackage* r = city_.remote()) r->setMode(static_cast<remote::LinkMode>(mode));
}

void Runtime::setRoute(const uint32_t* cells, size_t n) {
  if (n && !cells) throw Error(Status::InvalidArg, "blvd_set_route: cells is NULL");
  if (!residency_->setRoute(cells, n))
    throw Error(Status::InvalidArg, "route of " + std::to_string(n) + " cells: a cell is out of range or the route "
                                        "exceeds route_capacity (" + std::to_string(desc_.route_capacity) + ")");
}

bool Runtime::mapMissing(const core::Error& e) const {
  return e.status() == Status::Unavailable && city_.remote() && !referenceMode();
}

// Waits as frames would stream: the same steps, until the cell is resident
// and every table page they read has arrived.
void Runtime::waitResident(double timeout_ms) {
  if (!(timeout_ms >= 0)) throw Error(Status::InvalidArg, "blvd_wait_resident: timeout_ms must be >= 0");
  if (!ctx_->makeCurrent()) throw Error(Status::Misuse, "the GL context cannot be made current on this thread");
  terrain_->settle(cam_);
  if (referenceMode()) return draw_->ensureReferenceBlocks(*renderer_);
  const auto t0 = std::chrono::steady_clock::now();
  const stream::City::NoLinkWait no_wait;  // the map of where the vehicle is, waited for below
  const uint64_t errors = slots_->counters().load_errors;
  for (;;) {
    uint32_t cell = graph::kNone;
    std::string missing;
    try {
      double arc_m;
      cell = streamSteps(arc_m, 1e9);  // waiting: no per-frame upload budget
      if (cell == graph::kNone || slots_->resident(cell)) return;
    } catch (const Error& e) {
      if (!mapMissing(e)) throw;
      missing = e.what();
    }
    // A load that failed now, or earlier (the cell is not asked for again).
    if (slots_->counters().load_errors != errors || slots_->failed(cell))
      throw Error(Status::Corrupt, slots_->lastError());
    if (msSince(t0) > timeout_ms)
      throw Error(Status::Timeout, (missing.empty() ? "cell " + std::to_string(cell) : std::string("the map")) +
                                       " not resident after " + std::to_string(timeout_ms) + " ms" +
                                       (!missing.empty()              ? ": " + missing
                                        : slots_->counters().link_waits ? ": " + slots_->lastError()
                                                                        : ""));
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

void Runtime::stats(blvd_stats* out) const {
  blvd_stats s = stats_;
  s.struct_size = out->struct_size ? out->struct_size : sizeof s;
  const SlotCounters& c = slots_->counters();
  s.load_errors = c.load_errors;
  s.evictions = c.evictions;
  s.blocks_reused = c.blocks_reused;
  s.block_levels_copied = c.block_levels_copied;
  s.upload_ms = c.upload_ms;
  s.upload_ms_max = c.upload_ms_max;
  s.misses = draw_->misses();
  s.resident_cells = slots_->residentCount();
  s.gpu.capacity_bytes = gpu_capacity_;
  s.gpu.used_bytes = slots_->usedBytes();
  s.gpu.high_water_bytes = std::max(slots_->highWaterBytes(), s.gpu.used_bytes);
  s.staging.capacity_bytes = loader_->carvedBytes();
  s.staging.used_bytes = loader_->stagingUsed();
  s.staging.high_water_bytes = loader_->stagingHighWater();
  s.decode.high_water_bytes = loader_->decodeHighWater();
  s.table_bytes = city_.tableBytes();
  s.tracking_bytes = tracker_->bytes();
  s.terrain_bytes = plan_.terrain.cpu_bytes;
  s.terrain_tiles = draw_->terrainTiles();
  s.terrain_loads = terrain_->loads();
  s.terrain_load_errors = terrain_->loadErrors();
  s.loads = loader_->loads();
  s.prefetch_gap_waits = loader_->gapWaits();
  s.prefetch_gap_wait_ms = loader_->gapWaitMs();
  s.prefetch_kept_off_cpu = loader_->keptOffCpu();
  s.prefetch_share_waits = loader_->shareWaits();
  s.prefetch_share_wait_ms = loader_->shareWaitMs();
  s.loader_cpu_ms = loader_->cpuMs(false);
  s.prefetch_cpu_ms = loader_->cpuMs(true);
  s.link_waits = c.link_waits + map_waits_;
  if (const remote::RemotePackage* r = city_.remote()) {
    const remote::RemoteStats rs = r->stats();
    s.link_requests = rs.link.requests;
    s.link_bytes = rs.link.bytes;
    s.link_bytes_per_s = rs.throughput_bps;
    s.cache_hits = rs.cache.hits;
    s.cache_misses = rs.cache.misses;
    s.cache_bytes = rs.cache_bytes;
    s.package_changed = rs.changed ? 1 : 0;
    s.cached_ahead_m = link_prefetch_->cachedAheadM();
    s.prefetch_horizon_m = link_prefetch_->horizonM();
    s.cached_ahead_s = speed_mps_ > 0.5 ? s.cached_ahead_m / speed_mps_ : 0.0;
    s.link_table_bytes = rs.table_bytes;
    s.cache_evictions = rs.cache.evictions;
  }
  std::memcpy(out, &s, std::min<size_t>(s.struct_size, sizeof s));
}

void Runtime::info(blvd_runtime_info* out) const {
  blvd_runtime_info i{};
  i.struct_size = out->struct_size ? out->struct_size : sizeof i;
  i.backend = ctx_->name();
  i.gl_renderer = renderer_->glRenderer();
  i.gl_version = renderer_->glVersion();
  i.origin_lat = city_.header().origin_lat;
  i.origin_lon = city_.header().origin_lon;
  i.cell_count = city_.streets().cellCount();  // the tables', which frames and routes index, not the header's
  i.block_count = city_.blockCount();
  i.building_count = city_.header().building_count;
  i.triangle_count = city_.header().triangle_count;
  std::memcpy(out, &i, std::min<size_t>(i.struct_size, sizeof i));
}

}  // namespace blvd::runtime
