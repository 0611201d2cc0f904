// The only code implementing include/blvd/blvd.h: argument checks, status
// mapping, and a catch-all so no exception crosses the C boundary.
#include <cmath>
#include <cstring>
#include <new>
#include <string>

#include "blvd/blvd.h"
#include "capi/binding.h"
#include "core/sized.h"
#include "core/status.h"
#include "runtime/package_source.h"

namespace blvd::capi {
thread_local std::string t_create_error;  // blvd_last_error(NULL)
}  // namespace blvd::capi
using blvd::capi::guarded;
using blvd::capi::misuse;
using blvd::capi::nullArg;
using blvd::capi::t_create_error;

extern "C" {

uint32_t blvd_version_number(void) { return BLVD_VERSION_NUMBER; }

const char* blvd_version_string(void) {
#define BLVD_STR2(x) #x
#define BLVD_STR(x) BLVD_STR2(x)
  return BLVD_STR(BLVD_VERSION_MAJOR) "." BLVD_STR(BLVD_VERSION_MINOR) "." BLVD_STR(BLVD_VERSION_PATCH);
}

const char* blvd_status_string(blvd_status s) {
  if (s < 0 || s > BLVD_ERR_OFF_MAP) return "unknown status";
  return blvd::core::statusString(static_cast<blvd::core::Status>(s));
}

blvd_runtime_desc blvd_runtime_desc_defaults(const blvd_runtime_desc* in) {
  blvd_runtime_desc d{};
  if (in) {
    const size_t n = in->struct_size && in->struct_size < sizeof d ? in->struct_size : sizeof d;
    std::memcpy(&d, in, n);
  }
  d.struct_size = sizeof d;
  if (!d.width) d.width = 800;
  if (!d.height) d.height = 480;
  if (d.fov_y_deg == 0) d.fov_y_deg = 45.f;
  if (d.eye_height_m == 0) d.eye_height_m = 1.5f;
  if (d.far_m == 0) d.far_m = 3000.f;
  if (!d.memory_budget_bytes) d.memory_budget_bytes = 256ull << 20;
  if (!d.gpu_budget_bytes) d.gpu_budget_bytes = 512ull << 20;
  if (!d.max_resident_cells) d.max_resident_cells = 4;
  if (d.upload_budget_ms == 0) d.upload_budget_ms = 2.f;
  if (!d.ring_capacity) d.ring_capacity = 512;
  if (!d.route_capacity) d.route_capacity = 4096;
  if (d.lod_error_px == 0) d.lod_error_px = 1.f;
  if (d.min_render_scale == 0) d.min_render_scale = 1.f;
  if (d.prefetch_share == 0) d.prefetch_share = 0.1f;
  d.reserved0 = 0;
  return d;
}

namespace {
// A blvd_render_mode value a C host may pass (create and blvd_set_render_mode).
bool knownMode(int32_t m) { return m >= BLVD_MODE_BLVD && m <= BLVD_MODE_SINGLE; }

blvd_status invalid(const char* who, const char* what) {
  t_create_error = std::string(who) + ": " + what;
  return BLVD_ERR_INVALID_ARG;
}

// The view, frame and LOD fields of a descriptor with its defaults filled in.
blvd_status checkView(const blvd_runtime_desc& d, const char* who) {
  if (d.width > 16384 || d.height > 16384) return invalid(who, "width and height must be at most 16384");
  if (!(d.fov_y_deg > 1 && d.fov_y_deg < 179) || !(d.eye_height_m > 0 && d.eye_height_m < 1000) ||
      !(d.far_m > 10 && d.far_m < 1e6))
    return invalid(who, "fov_y_deg, eye_height_m or far_m out of range");
  if (!(d.target_frame_ms >= 0 && d.target_frame_ms < 10000) || !(d.lod_error_px > 0 && d.lod_error_px < 1e4))
    return invalid(who, "target_frame_ms or lod_error_px out of range");
  if (!(d.min_render_scale >= 0.25f && d.min_render_scale <= 1.f))
    return invalid(who, "min_render_scale must be within 0.25..1 (0 means 1)");
  if (!knownMode(blvd::core::rawEnum(d.mode))) return invalid(who, "unknown render mode");
  if (blvd::core::rawEnum(d.backend) < 0 || blvd::core::rawEnum(d.backend) > BLVD_CONTEXT_SHARED)
    return invalid(who, "unknown backend");
  return BLVD_OK;
}

// A descriptor with its defaults filled in, as create and memory_required take
// it: the pools it sizes are checked before anything is carved or measured.
blvd_status checkDesc(const blvd_runtime_desc& d, const char* who) {
  if (!d.package_path || !*d.package_path) return invalid(who, "desc.package_path is required");
  if (const blvd_status st = checkView(d, who); st != BLVD_OK) return st;
  if (d.max_resident_cells < 2 || d.max_resident_cells > 4096)
    return invalid(who, "max_resident_cells must be within 2..4096 (the current cell and one ahead)");
  if (!(d.upload_budget_ms > 0 && d.upload_budget_ms < 1000) || d.ring_capacity > (1u << 20) ||
      d.route_capacity > (1u << 24))
    return invalid(who, "upload_budget_ms, ring_capacity or route_capacity out of range");
  if (d.prefetch_priority != BLVD_PREFETCH_IDLE && d.prefetch_priority != BLVD_PREFETCH_LOW &&
      d.prefetch_priority != BLVD_PREFETCH_IDLE_ANYTIME)
    return invalid(who, "prefetch_priority must be BLVD_PREFETCH_IDLE, BLVD_PREFETCH_LOW or BLVD_PREFETCH_IDLE_ANYTIME");
  if (!(d.prefetch_share < 0 || (d.prefetch_share > 0 && d.prefetch_share <= 1)))
    return invalid(who, "prefetch_share must be within (0, 1], or negative for no bound (0 means 0.1)");
  if (!d.allocator.alloc != !d.allocator.free) return invalid(who, "allocator needs both alloc and free, or neither");
  if (d.impostor_texture != BLVD_TEXTURE_RGBA8 && d.impostor_texture != BLVD_TEXTURE_ETC2)
    return invalid(who, "impostor_texture must be BLVD_TEXTURE_RGBA8 or BLVD_TEXTURE_ETC2");
  return BLVD_OK;
}
}  // namespace

blvd_status blvd_runtime_create(const blvd_runtime_desc* desc, blvd_runtime** out) {
  if (!out) return nullArg(nullptr, "blvd_runtime_create: out is NULL");
  *out = nullptr;
  if (!desc) return nullArg(nullptr, "blvd_runtime_create: desc is NULL");
  t_create_error.clear();
  const blvd_runtime_desc d = blvd_runtime_desc_defaults(desc);
  if (const blvd_status st = checkDesc(d, "blvd_runtime_create"); st != BLVD_OK) return st;
  blvd::runtime::Runtime* impl = nullptr;
  const blvd_status st = guarded(nullptr, [&] { impl = new blvd::runtime::Runtime(d); });
  if (st != BLVD_OK) return st;
  *out = new (std::nothrow) blvd_runtime{impl};
  if (!*out) {
    delete impl;
    t_create_error = "out of memory";
    return BLVD_ERR_NOMEM;
  }
  return BLVD_OK;
}

blvd_status blvd_memory_required(const blvd_runtime_desc* desc, const char* package_path, uint64_t* cpu_bytes,
                                 uint64_t* gpu_bytes) {
  if (!desc || !cpu_bytes) return nullArg(nullptr, "blvd_memory_required: desc or cpu_bytes is NULL");
  t_create_error.clear();
  blvd_runtime_desc d = blvd_runtime_desc_defaults(desc);
  if (package_path) d.package_path = package_path;
  if (const blvd_status st = checkDesc(d, "blvd_memory_required"); st != BLVD_OK) return st;
  return guarded(nullptr, [&] {
    blvd::stream::City city;
    blvd::runtime::openCity(city, d.package_path, blvd::runtime::linkDesc(d), blvd::stream::City::Tables::All);
    const blvd::runtime::MemoryPlan plan = blvd::runtime::planMemory(d, city);
    *cpu_bytes = plan.cpu_bytes;
    if (gpu_bytes) *gpu_bytes = plan.gpu_bytes;
  });
}

void blvd_runtime_destroy(blvd_runtime* rt) {
  if (!rt) return;
  try {
    delete rt->impl;
  } catch (...) {
  }
  delete rt;
}

const char* blvd_last_error(const blvd_runtime* rt) {
  return rt ? rt->impl->last_error.c_str() : t_create_error.c_str();
}

blvd_status blvd_runtime_get_info(blvd_runtime* rt, blvd_runtime_info* info) {
  if (!rt) return misuse(nullptr, "blvd_runtime_get_info: rt is NULL");
  if (!info) return nullArg(rt, "blvd_runtime_get_info: info is NULL");
  return guarded(rt, [&] { rt->impl->info(info); });
}

blvd_status blvd_set_pose_geo(blvd_runtime* rt, double lat, double lon, float heading_deg, float pitch_deg) {
  if (!rt) return misuse(nullptr, "blvd_set_pose_geo: rt is NULL");
  return guarded(rt, [&] { rt->impl->setPoseGeo(lat, lon, heading_deg, pitch_deg); });
}

blvd_status blvd_set_camera_source(blvd_runtime* rt, blvd_camera_source source) {
  if (!rt) return misuse(nullptr, "blvd_set_camera_source: rt is NULL");
  const int32_t v = blvd::core::rawEnum(source);
  if (v != BLVD_CAMERA_HOST && v != BLVD_CAMERA_TRACKED) {
    rt->impl->last_error = "blvd_set_camera_source: unknown source " + std::to_string(v);
    return BLVD_ERR_INVALID_ARG;
  }
  return guarded(rt, [&] { rt->impl->setCameraSource(source); });
}

blvd_status blvd_set_pose_local(blvd_runtime* rt, double x, double y, float heading_deg, float pitch_deg) {
  if (!rt) return misuse(nullptr, "blvd_set_pose_local: rt is NULL");
  return guarded(rt, [&] { rt->impl->setPoseLocal(x, y, heading_deg, pitch_deg); });
}

blvd_status blvd_set_render_mode(blvd_runtime* rt, blvd_render_mode mode, float radius_m) {
  if (!rt) return misuse(nullptr, "blvd_set_render_mode: rt is NULL");
  const int32_t m = blvd::core::rawEnum(mode);
  if (!knownMode(m)) {
    rt->impl->last_error = "blvd_set_render_mode: unknown render mode " + std::to_string(m);
    return BLVD_ERR_INVALID_ARG;
  }
  return guarded(rt, [&] { rt->impl->setMode(mode, radius_m); });
}

blvd_status blvd_set_link_mode(blvd_runtime* rt, blvd_link_mode mode) {
  if (!rt) return misuse(nullptr, "blvd_set_link_mode: rt is NULL");
  const int32_t m = blvd::core::rawEnum(mode);
  if (m < BLVD_LINK_ONLINE || m > BLVD_LINK_OFFLINE) {
    rt->impl->last_error = "blvd_set_link_mode: unknown link mode " + std::to_string(m);
    return BLVD_ERR_INVALID_ARG;
  }
  return guarded(rt, [&] { rt->impl->setLinkMode(mode); });
}

blvd_status blvd_runtime_stats(blvd_runtime* rt, blvd_stats* stats) {
  if (!rt) return misuse(nullptr, "blvd_runtime_stats: rt is NULL");
  if (!stats) return nullArg(rt, "blvd_runtime_stats: stats is NULL");
  return guarded(rt, [&] { rt->impl->stats(stats); });
}

blvd_status blvd_render_views(blvd_runtime* rt, const blvd_view* views, uint32_t n, blvd_frame_stats* stats) {
  if (!rt) return misuse(nullptr, "blvd_render_views: rt is NULL");
  if (!views || n == 0 || n > 16) return nullArg(rt, "blvd_render_views: need 1..16 views");
  return guarded(rt, [&] { rt->impl->render(stats, views, n); });
}

blvd_status blvd_wait_resident(blvd_runtime* rt, double timeout_ms) {
  if (!rt) return misuse(nullptr, "blvd_wait_resident: rt is NULL");
  return guarded(rt, [&] { rt->impl->waitResident(timeout_ms); });
}

blvd_status blvd_set_route(blvd_runtime* rt, const uint32_t* cells, size_t n) {
  if (!rt) return misuse(nullptr, "blvd_set_route: rt is NULL");
  return guarded(rt, [&] { rt->impl->setRoute(cells, n); });
}

blvd_status blvd_render(blvd_runtime* rt, blvd_frame_stats* stats) {
  if (!rt) return misuse(nullptr, "blvd_render: rt is NULL");
  return guarded(rt, [&] { rt->impl->render(stats); });
}

blvd_status blvd_read_pixels(blvd_runtime* rt, void* rgba, size_t rgba_bytes) {
  if (!rt) return misuse(nullptr, "blvd_read_pixels: rt is NULL");
  if (!rgba) return nullArg(rt, "blvd_read_pixels: rgba is NULL");
  return guarded(rt, [&] { rt->impl->readPixels(rgba, rgba_bytes); });
}

blvd_status blvd_read_items(blvd_runtime* rt, uint32_t* ids, size_t count) {
  if (!rt) return misuse(nullptr, "blvd_read_items: rt is NULL");
  if (!ids) return nullArg(rt, "blvd_read_items: ids is NULL");
  return guarded(rt, [&] { rt->impl->readItems(ids, count); });
}

}  // extern "C"
