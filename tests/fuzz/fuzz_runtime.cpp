// Fuzz target for the C API's runtime (blvd_memory_required, blvd_runtime_*):
// the input is a descriptor and a script of calls on the runtime it creates,
// over a small street-grid package (seed_package.h), as a host would make them.
// - The descriptor is the fuzzer's bytes but for its pointers (the package, a
//   missing file or none; blvd's allocator or one that fails at the fuzzer's
//   n-th call; no executor, no cache folder) and its budgets, held to 1 GiB
//   (a head unit's; a bigger one is what a host asked for). blvd_memory_required
//   and blvd_runtime_create return a status of the enum and, failing, a reason;
//   create succeeds only where memory_required did. Frames over 64 x 64 go to
//   blvd_memory_required only: their pixels would cost time, not find bugs.
// - Then poses (near the package or anywhere), routes, render modes, frames
//   and views, reads of pixels and item ids into buffers of the fuzzer's size,
//   feeds, a start pose, calibrations, stats and info of any struct_size: every
//   call returns a status of the enum, writes nothing past what it was given,
//   and one that fails on the render thread says why.
//
// Seeds: set BLVD_FUZZ_SEED_DIR and the target writes a few scripts there (a
// drive of frames and views, a host allocator failing, a descriptor refused).
// BLVD_FUZZ_TRACE=1 prints each call, to read a crash's script.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "bake/pool_sizing.h"
#include "blvd/blvd.h"
#include "fuzz_script.h"
#include "seed_package.h"

namespace {

using blvd_fuzz::Script;

std::string g_package;  // the grid package, written once per process
bool g_trace = false;

constexpr uint32_t kMaxSide = 64;           // frames created: at most this wide and tall
constexpr uint64_t kMaxBudget = 1ull << 30; // memory and GPU budgets

// A host allocator that fails from its n-th call on (n = 0: never).
struct FailingAllocator {
  uint32_t calls = 0, fail_at = 0;
};

void* failingAlloc(size_t size, size_t align, void* user) {
  auto* a = static_cast<FailingAllocator*>(user);
  if (a->fail_at && ++a->calls >= a->fail_at) return nullptr;
  return std::aligned_alloc(align, (size + align - 1) / align * align);
}

void failingFree(void* p, void*) { std::free(p); }

// The descriptor: the fuzzer's bytes, then the pointers and budgets set as
// the header above says.
blvd_runtime_desc readDesc(Script& sc, FailingAllocator& alloc) {
  blvd_runtime_desc d = sc.in<blvd_runtime_desc>();
  const uint8_t how = sc.byte();
  d.package_path = (how & 3) == 0 ? nullptr : (how & 3) == 1 ? "/nonexistent/city.blvd" : g_package.c_str();
  d.allocator = {};
  if (how & 4) {
    alloc.fail_at = sc.byte();
    d.allocator = {failingAlloc, failingFree, &alloc};
  }
  d.executor = {};
  d.cache_path = nullptr;
  d.memory_budget_bytes %= kMaxBudget + 1;
  d.gpu_budget_bytes %= kMaxBudget + 1;
  return d;
}

void checkStatus(blvd_status s, const blvd_runtime* rt, bool says_why = true) {
  if (g_trace && s != BLVD_OK) std::fprintf(stderr, "  -> %d: %s\n", s, blvd_last_error(rt));
  if (!blvd_fuzz::known(s)) std::abort();
  if (says_why && s != BLVD_OK && blvd_last_error(rt)[0] == '\0') std::abort();
}

// An output struct of the fuzzer's struct_size; true when the call succeeded
// and filled all of it.
template <typename T, typename Call>
bool out(Script& sc, T& v, blvd_runtime* rt, Call&& call) {
  const blvd_fuzz::OutResult r = blvd_fuzz::callOut(sc, v, call);
  checkStatus(r.status, rt);
  return r.status == BLVD_OK && r.whole;
}

struct Frame {
  uint32_t width, height, cells;
  double lat, lon;  // the package's origin
};

void checkFrameStats(const blvd_frame_stats& f, const Frame& fr) {
  if (g_trace) std::fprintf(stderr, "  frame %g ms, cell %u of %u, flags %x\n", f.frame_ms, f.cell, fr.cells, f.flags);
  if (!(f.frame_ms >= 0) || !std::isfinite(f.frame_ms)) std::abort();
  if (f.cell != BLVD_NO_CELL && f.cell >= fr.cells) std::abort();
}

// A buffer of the fuzzer's size around `need` bytes, with canaries after it.
template <typename Call>
void readInto(Script& sc, size_t need, blvd_runtime* rt, Call&& call) {
  const size_t size = need - std::min<size_t>(need, 8) + sc.byte() % 17;
  std::vector<uint8_t> buf(size + 64, 0xA5);
  checkStatus(call(buf.data(), size), rt);
  for (size_t i = size; i < buf.size(); ++i)
    if (buf[i] != 0xA5) std::abort();
}

void setPose(Script& sc, blvd_runtime* rt, const Frame& fr, bool geo) {
  double a, b;
  float heading, pitch;
  const bool near = sc.byte() & 1;
  sc.take(&a, sizeof a);
  sc.take(&b, sizeof b);
  sc.take(&heading, sizeof heading);
  sc.take(&pitch, sizeof pitch);
  if (near) {  // within about a kilometre of the origin, where the streets are
    a = std::isfinite(a) ? std::fmod(a, 1000.0) : 0;
    b = std::isfinite(b) ? std::fmod(b, 1000.0) : 0;
    if (geo) a = fr.lat + a / 111132.0, b = fr.lon + b / 80500.0;
  }
  if (g_trace) std::fprintf(stderr, "pose %s %g %g %g %g\n", geo ? "geo" : "local", a, b, heading, pitch);
  checkStatus(geo ? blvd_set_pose_geo(rt, a, b, heading, pitch) : blvd_set_pose_local(rt, a, b, heading, pitch), rt);
}

void setRoute(Script& sc, blvd_runtime* rt, const Frame& fr) {
  const size_t n = sc.byte() % 33;
  std::vector<uint32_t> cells(n);
  for (auto& c : cells) c = sc.byte() % (fr.cells + 2);  // some past the last cell
  checkStatus(blvd_set_route(rt, n ? cells.data() : nullptr, n), rt);
}

void renderViews(Script& sc, blvd_runtime* rt, const Frame& fr) {
  const uint32_t n = sc.byte() % 18;  // 0 and 17 are refused
  std::vector<blvd_view> views(n);
  for (auto& v : views) v = sc.in<blvd_view>();
  blvd_frame_stats st;
  if (out(sc, st, rt, [&](blvd_frame_stats* o) { return blvd_render_views(rt, n ? views.data() : nullptr, n, o); }))
    checkFrameStats(st, fr);
}

// Calls that draw or read what was drawn.
void frameStep(Script& sc, blvd_runtime* rt, const Frame& fr, int op) {
  switch (op) {
    case 0: setPose(sc, rt, fr, true); break;
    case 1: setPose(sc, rt, fr, false); break;
    case 2: setRoute(sc, rt, fr); break;
    case 3: {
      int32_t mode;
      float radius;
      sc.take(&mode, sizeof mode);
      sc.take(&radius, sizeof radius);
      checkStatus(blvd_set_render_mode(rt, static_cast<blvd_render_mode>(mode % 6), radius), rt);
      break;
    }
    case 4: {
      blvd_frame_stats st;
      if (out(sc, st, rt, [&](blvd_frame_stats* o) { return blvd_render(rt, o); })) checkFrameStats(st, fr);
      break;
    }
    case 5: renderViews(sc, rt, fr); break;
    case 6:
      readInto(sc, size_t(fr.width) * fr.height * 4, rt, [&](uint8_t* p, size_t n) { return blvd_read_pixels(rt, p, n); });
      break;
    default:
      readInto(sc, size_t(fr.width) * fr.height * 4, rt,
               [&](uint8_t* p, size_t n) { return blvd_read_items(rt, reinterpret_cast<uint32_t*>(p), n / 4); });
      break;
  }
}

// Calls that feed, track, wait and report.
void trackStep(Script& sc, blvd_runtime* rt, int op) {
  switch (op) {
    case 0: {
      const blvd_gnss_fix f = sc.in<blvd_gnss_fix>();
      checkStatus(blvd_feed_gnss(rt, &f), rt, false);  // feeds set no text (any thread)
      break;
    }
    case 1: {
      const blvd_odometry o = sc.in<blvd_odometry>();
      checkStatus(blvd_feed_odometry(rt, &o), rt, false);
      break;
    }
    case 2: {
      double t;
      sc.take(&t, sizeof t);
      blvd_pose p;
      if (out(sc, p, rt, [&](blvd_pose* o) { return blvd_get_pose(rt, t, o); }) && (p.flags & BLVD_POSE_VALID) &&
          (!std::isfinite(p.x) || !std::isfinite(p.y) || !(std::fabs(p.lat) <= 90)))
        std::abort();
      break;
    }
    case 3: {
      const blvd_start_pose sp = sc.in<blvd_start_pose>();
      checkStatus(blvd_set_start_pose(rt, &sp), rt);
      break;
    }
    case 4: {
      int32_t source;
      sc.take(&source, sizeof source);
      checkStatus(blvd_set_camera_source(rt, static_cast<blvd_camera_source>(source % 3)), rt);
      break;
    }
    case 5: {
      double ms;  // any value, but no wait past 20 ms
      sc.take(&ms, sizeof ms);
      if (ms > 20) ms = 20;
      checkStatus(blvd_wait_resident(rt, ms), rt);
      break;
    }
    case 6: {
      blvd_stats st;
      if (out(sc, st, rt, [&](blvd_stats* o) { return blvd_runtime_stats(rt, o); }) &&
          st.resident_cells > st.max_resident_cells)
        std::abort();
      break;
    }
    case 7: {
      blvd_runtime_info info;
      out(sc, info, rt, [&](blvd_runtime_info* o) { return blvd_runtime_get_info(rt, o); });
      break;
    }
    case 8: {
      blvd_tracking_stats st;
      out(sc, st, rt, [&](blvd_tracking_stats* o) { return blvd_get_tracking_stats(rt, o); });
      break;
    }
    default: {
      const blvd_odometry_calibration c = sc.in<blvd_odometry_calibration>();
      checkStatus(blvd_set_odometry_calibration(rt, &c), rt);
      blvd_odometry_calibration got;
      out(sc, got, rt, [&](blvd_odometry_calibration* o) { return blvd_get_odometry_calibration(rt, o); });
      break;
    }
  }
}

void drive(Script& sc, blvd_runtime* rt, const blvd_runtime_desc& d) {
  blvd_runtime_info info{};
  info.struct_size = sizeof info;
  if (blvd_runtime_get_info(rt, &info) != BLVD_OK) std::abort();
  const Frame fr{d.width, d.height, info.cell_count, info.origin_lat, info.origin_lon};
  for (int calls = 0; !sc.done() && calls < 64; ++calls) {
    const int op = sc.byte() % 18;
    if (g_trace) std::fprintf(stderr, "op %d\n", op);
    if (op < 8)
      frameStep(sc, rt, fr, op);
    else
      trackStep(sc, rt, op - 8);
  }
}

void writeSeed(const std::filesystem::path& dir, const char* name, const std::vector<uint8_t>& s) {
  std::ofstream(dir / name, std::ios::binary).write(reinterpret_cast<const char*>(s.data()),
                                                    static_cast<std::streamsize>(s.size()));
}

template <typename T>
void put(std::vector<uint8_t>& s, const T& v) {
  const auto* b = reinterpret_cast<const uint8_t*>(&v);
  s.insert(s.end(), b, b + sizeof v);
}

// A 48 x 32 runtime on the package (a host allocator failing at `fail_at`,
// 0: never), driven along the middle street: a pose, a frame, its pixels and
// ids, two views, a fix, the stats.
std::vector<uint8_t> driveSeed(uint8_t fail_at) {
  blvd_runtime_desc d{};
  d.struct_size = sizeof d;
  d.width = 48;
  d.height = 32;
  d.backend = BLVD_BACKEND_EGL_SURFACELESS;
  std::vector<uint8_t> s;
  put(s, d);
  s.push_back(fail_at ? 2 | 4 : 2);
  if (fail_at) s.push_back(fail_at);
  for (int k = 0; k < 3; ++k) {
    s.push_back(1);  // a local pose, near
    s.push_back(1);
    put(s, 0.0);
    put(s, 20.0 * k);
    put(s, 0.f);
    put(s, 0.f);
    s.push_back(13);  // wait until the cell is resident, 20 ms at most
    put(s, 20.0);
    s.insert(s.end(), {4, 0, 6, 8, 7, 8});  // a frame, its pixels, its ids
  }
  blvd_view v[2]{};
  v[0].struct_size = v[1].struct_size = sizeof v[0];
  v[1].yaw_offset_deg = 180;
  v[1].width = 16, v[1].height = 8;
  s.insert(s.end(), {5, 2});
  put(s, v);
  s.push_back(0);
  blvd_gnss_fix f{};
  f.struct_size = sizeof f;
  f.t = 1, f.lat = 43.73, f.lon = 7.42, f.mode = BLVD_GNSS_MODE_3D, f.flags = BLVD_GNSS_HAS_LATLON;
  s.push_back(8);
  put(s, f);
  s.insert(s.end(), {14, 0});  // stats
  return s;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  g_trace = std::getenv("BLVD_FUZZ_TRACE") != nullptr;
  setenv("LP_NUM_THREADS", "0", 0);  // llvmpipe draws on the calling thread: no rasterizer threads a run
  const std::filesystem::path tmp = std::filesystem::temp_directory_path() / "blvd_fuzz_runtime_grid.blvd";
  blvd_test::writeGridPackage(tmp.string(), blvd::bake::fillPoolSizing);
  g_package = tmp.string();
  const char* dir = std::getenv("BLVD_FUZZ_SEED_DIR");
  if (!dir || !*dir) return 0;
  std::filesystem::create_directories(dir);
  writeSeed(dir, "drive.bin", driveSeed(0));
  writeSeed(dir, "nomem.bin", driveSeed(3));
  blvd_runtime_desc d{};
  d.struct_size = sizeof d;
  d.width = 40000;  // refused by the plan, never created
  d.height = 40000;
  d.max_resident_cells = 1;
  std::vector<uint8_t> s;
  put(s, d);
  s.push_back(2);
  writeSeed(dir, "refused.bin", s);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Script sc{data, size};
  FailingAllocator alloc;
  const blvd_runtime_desc d = readDesc(sc, alloc);
  uint64_t cpu = 0, gpu = 0;
  const blvd_status need = blvd_memory_required(&d, nullptr, &cpu, &gpu);
  if (g_trace) std::fprintf(stderr, "memory_required %d %llu %llu: %s\n", need, (unsigned long long)cpu,
                            (unsigned long long)gpu, blvd_last_error(nullptr));
  checkStatus(need, nullptr);
  if (d.width == 0 || d.height == 0 || d.width > kMaxSide || d.height > kMaxSide) return 0;
  blvd_runtime* rt = nullptr;
  const blvd_status s = blvd_runtime_create(&d, &rt);
  if (g_trace) std::fprintf(stderr, "create %d: %s\n", s, blvd_last_error(nullptr));
  if ((s == BLVD_OK) != (rt != nullptr)) std::abort();
  checkStatus(s, nullptr);
  if (s != BLVD_OK) return 0;
  if (need != BLVD_OK) std::abort();  // created what memory_required refused
  drive(sc, rt, d);
  blvd_runtime_destroy(rt);
  return 0;
}
