// Fuzz target for the C API's struct inputs on a tracker (blvd_tracker_*):
// the input is a script of calls whose structs (fixes, odometry, start poses,
// calibrations, and the struct_size of every struct in or out) are the
// fuzzer's bytes, on a tracker over a small street-grid package or over an
// origin alone. Every call must return a status of the enum, never crash or
// hang; an output struct is written up to its struct_size and not a byte
// past; a valid pose has finite coordinates on the globe; a failed call says why.
//
// Seeds: set BLVD_FUZZ_SEED_DIR and the target writes a few scripts there (a
// drive of fixes and odometry, a start pose, a calibration, the getters).
// BLVD_FUZZ_TRACE=1 prints each call and its struct, to read a crash's script.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "blvd/blvd.h"
#include "fuzz_script.h"
#include "seed_package.h"

namespace {

std::string g_package;  // the grid package, written once per process
bool g_trace = false;   // BLVD_FUZZ_TRACE=1: print each call, to read a crash's script

using blvd_fuzz::Script;

void checkStatus(blvd_status s, blvd_tracker* tr) {
  if (!blvd_fuzz::known(s)) std::abort();
  if (s != BLVD_OK && s != BLVD_ERR_MISUSE && blvd_tracker_last_error(tr)[0] == '\0') std::abort();
}

// An output struct of the fuzzer's struct_size: true when the call succeeded
// and filled all of it.
template <typename T, typename Call>
bool out(Script& sc, T& v, Call&& call, blvd_tracker* tr) {
  const blvd_fuzz::OutResult r = blvd_fuzz::callOut(sc, v, call);
  checkStatus(r.status, tr);
  return r.status == BLVD_OK && r.whole;
}

void checkPose(const blvd_pose& p) {
  if (!(p.flags & BLVD_POSE_VALID)) return;
  if (g_trace)
    std::fprintf(stderr, "pose t %g x %g y %g lat %g lon %g cam %g %g hdg %g sigma %g conf %g flags %x\n", p.t, p.x, p.y,
                 p.lat, p.lon, p.camera_x, p.camera_y, p.heading_deg, p.pos_sigma_m, p.confidence, p.flags);
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !(std::fabs(p.lat) <= 90) || !(std::fabs(p.lon) <= 180)) std::abort();
  if (!std::isfinite(p.camera_x) || !std::isfinite(p.camera_y) || !std::isfinite(p.heading_deg)) std::abort();
  if (!(p.pos_sigma_m >= 0) || !(p.confidence >= 0 && p.confidence <= 1)) std::abort();
}

void step(Script& sc, blvd_tracker* tr) {
  const int op = sc.byte() % 7;
  if (g_trace) std::fprintf(stderr, "op %d\n", op);
  switch (op) {
    case 0: {
      const blvd_gnss_fix f = sc.in<blvd_gnss_fix>();
      if (g_trace)
        std::fprintf(stderr, "fix size %u t %g lat %g lon %g speed %g track %g hdop %g hacc %g mode %d flags %x\n",
                     f.struct_size, f.t, f.lat, f.lon, f.speed_mps, f.track_deg, f.hdop, f.h_acc_m, f.mode, f.flags);
      checkStatus(blvd_tracker_feed_gnss(tr, &f), tr);
      break;
    }
    case 1: {
      const blvd_odometry o = sc.in<blvd_odometry>();
      if (g_trace)
        std::fprintf(stderr, "odo size %u t %g v %g yaw %g wheels %g %g %g %g hdg %g rev %d flags %x\n", o.struct_size, o.t,
                     o.speed_mps, o.yaw_rate_dps, o.wheel_speeds_mps[0], o.wheel_speeds_mps[1], o.wheel_speeds_mps[2],
                     o.wheel_speeds_mps[3], o.heading_deg, o.reverse, o.flags);
      checkStatus(blvd_tracker_feed_odometry(tr, &o), tr);
      break;
    }
    case 2: {
      double t;
      sc.take(&t, sizeof t);
      if (g_trace) std::fprintf(stderr, "get_pose t %g\n", t);
      blvd_pose p;
      if (out(sc, p, [&](blvd_pose* o) { return blvd_tracker_get_pose(tr, t, o); }, tr)) checkPose(p);
      break;
    }
    case 3: {
      const blvd_start_pose sp = sc.in<blvd_start_pose>();
      if (g_trace)
        std::fprintf(stderr, "start size %u t %g lat %g lon %g hdg %g sigma %g hsigma %g\n", sp.struct_size, sp.t, sp.lat,
                     sp.lon, sp.heading_deg, sp.sigma_m, sp.heading_sigma_deg);
      checkStatus(blvd_tracker_set_start_pose(tr, &sp), tr);
      break;
    }
    case 4: {
      const blvd_odometry_calibration c = sc.in<blvd_odometry_calibration>();
      checkStatus(blvd_tracker_set_odometry_calibration(tr, &c), tr);
      break;
    }
    case 5: {
      blvd_odometry_calibration c;
      if (out(sc, c, [&](blvd_odometry_calibration* o) { return blvd_tracker_get_odometry_calibration(tr, o); }, tr) &&
          !(c.speed_scale >= 0.5 && c.speed_scale <= 2))
        std::abort();
      break;
    }
    default: {
      blvd_tracking_stats st;
      if (out(sc, st, [&](blvd_tracking_stats* o) { return blvd_tracker_get_stats(tr, o); }, tr) &&
          st.gnss_used + st.gnss_rejected + st.gnss_ignored + st.gnss_duplicates > st.gnss_fed)
        std::abort();
      break;
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  g_trace = std::getenv("BLVD_FUZZ_TRACE") != nullptr;
  const std::filesystem::path tmp = std::filesystem::temp_directory_path() / "blvd_fuzz_capi_grid.blvd";
  blvd_test::writeGridPackage(tmp.string());
  g_package = tmp.string();
  const char* dir = std::getenv("BLVD_FUZZ_SEED_DIR");
  if (!dir || !*dir) return 0;
  std::filesystem::create_directories(dir);
  // A drive north along the grid's middle street: a fix and an odometry sample
  // a second, a pose after each; then the getters.
  std::vector<uint8_t> s;
  const auto put = [&](const void* p, size_t n) {
    const uint8_t* b = static_cast<const uint8_t*>(p);
    s.insert(s.end(), b, b + n);
  };
  s.push_back(1);  // with the package
  for (int k = 0; k < 8; ++k) {
    blvd_gnss_fix f{};
    f.struct_size = sizeof f;
    f.t = 10 + k;
    f.lat = 43.73 + (k * 10.0) / 111132.0;
    f.lon = 7.42 + 50.0 / 80500.0;
    f.speed_mps = 10;
    f.hdop = 1;
    f.mode = BLVD_GNSS_MODE_3D;
    f.flags = BLVD_GNSS_HAS_LATLON | BLVD_GNSS_HAS_SPEED | BLVD_GNSS_HAS_TRACK | BLVD_GNSS_HAS_HDOP;
    s.push_back(0);
    put(&f, sizeof f);
    blvd_odometry o{};
    o.struct_size = sizeof o;
    o.t = 10.5 + k;
    o.speed_mps = 10;
    o.flags = BLVD_ODO_SPEED | BLVD_ODO_YAW_RATE;
    s.push_back(1);
    put(&o, sizeof o);
    s.push_back(2);
    const double t = 10.5 + k;
    put(&t, sizeof t);
    s.push_back(0);  // the whole pose
  }
  for (uint8_t op : {5, 6}) s.insert(s.end(), {op, 0});
  std::ofstream(std::filesystem::path(dir) / "drive.bin", std::ios::binary).write(reinterpret_cast<const char*>(s.data()),
                                                                                 static_cast<std::streamsize>(s.size()));
  s.assign({0});  // no package: an origin, a start pose, a calibration, a pose
  const double origin[2] = {43.73, 7.42};
  put(origin, sizeof origin);
  blvd_start_pose sp{};
  sp.struct_size = sizeof sp;
  sp.t = 5;
  sp.lat = 43.73;
  sp.lon = 7.42;
  sp.heading_deg = 90;
  s.push_back(3);
  put(&sp, sizeof sp);
  blvd_odometry_calibration c{};
  c.struct_size = sizeof c;
  c.speed_scale = 1.02;
  s.push_back(4);
  put(&c, sizeof c);
  const double t = 6;
  s.push_back(2);
  put(&t, sizeof t);
  s.push_back(0);
  std::ofstream(std::filesystem::path(dir) / "start.bin", std::ios::binary).write(reinterpret_cast<const char*>(s.data()),
                                                                                 static_cast<std::streamsize>(s.size()));
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Script sc{data, size};
  blvd_tracker_desc d{};
  const uint8_t mode = sc.byte();
  d.struct_size = sizeof d;
  if (mode & 1) {
    d.package_path = g_package.c_str();
  } else {
    sc.take(&d.origin_lat, sizeof d.origin_lat);
    sc.take(&d.origin_lon, sizeof d.origin_lon);
  }
  d.ring_capacity = mode >> 1;  // 0 (the default, 512) to 127: a ring that fills
  blvd_tracker* tr = nullptr;
  const blvd_status s = blvd_tracker_create(&d, &tr);
  if (g_trace) std::fprintf(stderr, "create %d: %s\n", s, blvd_last_error(nullptr));
  if ((s == BLVD_OK) != (tr != nullptr)) std::abort();
  if (s != BLVD_OK) {
    if (blvd_last_error(nullptr)[0] == '\0') std::abort();
    return 0;
  }
  for (int calls = 0; !sc.done() && calls < 256; ++calls) step(sc, tr);
  blvd_tracker_destroy(tr);
  return 0;
}
