// The tracking part of the C API, on a runtime (blvd_feed_*, blvd_get_pose,
// ...) and on a tracker without a renderer (blvd_tracker_*): both drive a
// track::Tracker, and the C structs become sdk/track's through
// track_convert.h, checked here once for both.
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <memory>
#include <string>

#include "capi/binding.h"
#include "capi/track_convert.h"
#include "runtime/package_source.h"
#include "stream/city.h"
#include "track/tracker.h"

// A tracker without a renderer: the package's graph (none: fusion only), its
// local frame, and the tracker over them.
struct blvd_tracker {
  std::unique_ptr<blvd::stream::City> city;  // graph and cells only; null without a package
  blvd::geo::LocalFrame frame{0, 0};
  std::unique_ptr<blvd::track::Tracker> tracker;
  double eye_height_m = 1.5;
  std::string last_error;
};

using blvd::capi::guarded;
using blvd::capi::misuse;
using blvd::capi::nullArg;
using blvd::capi::t_create_error;
namespace core = blvd::core;
namespace track = blvd::track;

namespace {

// Every field of these input structs is needed (they have no defaults): a
// struct_size of 0 (this header's size) or one that covers them all.
void needStructSize(const char* fn, uint32_t got, size_t needed) {
  if (got != 0 && got < needed)
    throw core::Error(core::Status::InvalidArg, std::string(fn) + ": struct_size " + std::to_string(got) +
                                                    " is smaller than the " + std::to_string(needed) +
                                                    " bytes it needs");
}

void setCalibration(track::Tracker& tr, const char* fn, const blvd_odometry_calibration& cal) {
  needStructSize(fn, cal.struct_size, offsetof(blvd_odometry_calibration, yaw_rate_bias_sigma_dps) + sizeof(double));
  if (tr.setCalibration(blvd::capi::toTrack(cal))) return;
  char msg[256];
  std::snprintf(msg, sizeof msg,
                "%s: speed_scale %g +- %g, yaw_rate_bias_dps %g +- %g: the scale must lie in [0.5, 2], the bias "
                "within 10 deg/s, the sigmas finite and not negative",
                fn, cal.speed_scale, cal.speed_scale_sigma, cal.yaw_rate_bias_dps, cal.yaw_rate_bias_sigma_dps);
  throw core::Error(core::Status::InvalidArg, msg);
}

// The start pose checked and converted; `start` applies it (false: refused).
template <typename Start>
void setStartPose(const char* fn, const blvd_start_pose& sp, Start&& start) {
  needStructSize(fn, sp.struct_size, offsetof(blvd_start_pose, heading_sigma_deg) + sizeof(double));
  if (start(blvd::capi::toTrack(sp))) return;
  char msg[512];
  std::snprintf(msg, sizeof msg,
                "%s: t %g, lat %g, lon %g, heading %g deg, sigma %g m, heading sigma %g deg: every field must be "
                "finite, lat within 90, lon within 180, the heading within 720, the sigmas not negative, the "
                "position's at most 10 km and the heading's at most 180 deg",
                fn, sp.t, sp.lat, sp.lon, sp.heading_deg, sp.sigma_m, sp.heading_sigma_deg);
  throw core::Error(core::Status::InvalidArg, msg);
}

// guarded() for a tracker: exceptions into a status and the tracker's last error.
template <typename F>
blvd_status trackerGuarded(blvd_tracker* tr, F&& f) {
  try {
    f();
    tr->last_error.clear();
    return BLVD_OK;
  } catch (const core::Error& e) {
    tr->last_error = e.what();
    return blvd::capi::toStatus(e.status());
  } catch (const std::exception& e) {
    tr->last_error = std::string("internal error: ") + e.what();
    return BLVD_ERR_INTERNAL;
  }
}

// A feed: any thread, so no last error is written; nothing may escape.
template <typename F>
blvd_status feedGuarded(F&& f) {
  try {
    f();
    return BLVD_OK;
  } catch (...) {
    return BLVD_ERR_INTERNAL;
  }
}

blvd_status badTrackerDesc(const char* why) {
  t_create_error = std::string("blvd_tracker_create: ") + why;
  return BLVD_ERR_INVALID_ARG;
}

}  // namespace

extern "C" {

// ---- On a runtime.

blvd_status blvd_feed_gnss(blvd_runtime* rt, const blvd_gnss_fix* fix) {
  if (!rt) return BLVD_ERR_MISUSE;  // no last error: feeds may run on any thread
  if (!fix) return BLVD_ERR_INVALID_ARG;
  return feedGuarded([&] { rt->impl->feedGnss(blvd::capi::toTrack(*fix)); });
}

blvd_status blvd_feed_odometry(blvd_runtime* rt, const blvd_odometry* odo) {
  if (!rt) return BLVD_ERR_MISUSE;
  if (!odo) return BLVD_ERR_INVALID_ARG;
  return feedGuarded([&] { rt->impl->feedOdometry(blvd::capi::toTrack(*odo)); });
}

blvd_status blvd_get_pose(blvd_runtime* rt, double t, blvd_pose* pose) {
  if (!rt) return misuse(nullptr, "blvd_get_pose: rt is NULL");
  if (!pose) return nullArg(rt, "blvd_get_pose: pose is NULL");
  return guarded(rt, [&] { blvd::capi::toBlvd(rt->impl->pose(t), rt->impl->frame(), pose); });
}

blvd_status blvd_get_odometry_calibration(blvd_runtime* rt, blvd_odometry_calibration* cal) {
  if (!rt) return misuse(nullptr, "blvd_get_odometry_calibration: rt is NULL");
  if (!cal) return nullArg(rt, "blvd_get_odometry_calibration: cal is NULL");
  return guarded(rt, [&] { blvd::capi::toBlvd(rt->impl->tracker().calibration(), cal); });
}

blvd_status blvd_set_odometry_calibration(blvd_runtime* rt, const blvd_odometry_calibration* cal) {
  if (!rt) return misuse(nullptr, "blvd_set_odometry_calibration: rt is NULL");
  if (!cal) return nullArg(rt, "blvd_set_odometry_calibration: cal is NULL");
  return guarded(rt, [&] { setCalibration(rt->impl->tracker(), "blvd_set_odometry_calibration", *cal); });
}

blvd_status blvd_set_start_pose(blvd_runtime* rt, const blvd_start_pose* sp) {
  if (!rt) return misuse(nullptr, "blvd_set_start_pose: rt is NULL");
  if (!sp) return nullArg(rt, "blvd_set_start_pose: sp is NULL");
  return guarded(rt, [&] {
    setStartPose("blvd_set_start_pose", *sp, [&](const track::StartPose& s) { return rt->impl->setStartPose(s); });
  });
}

blvd_status blvd_get_tracking_stats(blvd_runtime* rt, blvd_tracking_stats* stats) {
  if (!rt) return misuse(nullptr, "blvd_get_tracking_stats: rt is NULL");
  if (!stats) return nullArg(rt, "blvd_get_tracking_stats: stats is NULL");
  return guarded(rt, [&] { blvd::capi::toBlvd(rt->impl->tracker().stats(), stats); });
}

// ---- On a tracker.

blvd_status blvd_tracker_create(const blvd_tracker_desc* desc, blvd_tracker** out) {
  if (!out) {
    t_create_error = "blvd_tracker_create: out is NULL";
    return BLVD_ERR_INVALID_ARG;
  }
  *out = nullptr;
  if (!desc) {
    t_create_error = "blvd_tracker_create: desc is NULL";
    return BLVD_ERR_INVALID_ARG;
  }
  t_create_error.clear();
  const blvd_tracker_desc d = core::sized(*desc);
  const bool has_package = d.package_path && *d.package_path;
  if (!has_package && !(std::fabs(d.origin_lat) <= 90 && std::fabs(d.origin_lon) <= 180))
    return badTrackerDesc("without a package, origin_lat must lie within 90 and origin_lon within 180 degrees");
  if (!(d.eye_height_m >= 0 && d.eye_height_m < 1000)) return badTrackerDesc("eye_height_m out of range");
  if (d.ring_capacity > (1u << 20)) return badTrackerDesc("ring_capacity is above 1048576");
  std::unique_ptr<blvd_tracker> tr;
  const blvd_status st = guarded(nullptr, [&] {
    tr = std::make_unique<blvd_tracker>();  // its members allocate too (the local frame)
    track::TrackerDesc td;
    td.eye_height_m = tr->eye_height_m = d.eye_height_m > 0 ? d.eye_height_m : 1.5;
    td.ring_capacity = d.ring_capacity ? d.ring_capacity : 512;
    if (has_package) {
      tr->city = std::make_unique<blvd::stream::City>();
      blvd::runtime::openCity(*tr->city, d.package_path, blvd::runtime::linkDesc(d), blvd::stream::City::Tables::Graph);
      tr->frame = tr->city->frame();
    } else {
      tr->frame = blvd::geo::LocalFrame(d.origin_lat, d.origin_lon);
    }
    tr->tracker = std::make_unique<track::Tracker>(tr->frame, tr->city ? &tr->city->streets() : nullptr, td);
  });
  if (st != BLVD_OK) return st;
  *out = tr.release();
  return BLVD_OK;
}

void blvd_tracker_destroy(blvd_tracker* tr) { delete tr; }

const char* blvd_tracker_last_error(const blvd_tracker* tr) {
  return tr ? tr->last_error.c_str() : t_create_error.c_str();
}

blvd_status blvd_tracker_feed_gnss(blvd_tracker* tr, const blvd_gnss_fix* fix) {
  if (!tr) return BLVD_ERR_MISUSE;
  if (!fix) return BLVD_ERR_INVALID_ARG;
  return feedGuarded([&] { tr->tracker->feedGnss(blvd::capi::toTrack(*fix)); });
}

blvd_status blvd_tracker_feed_odometry(blvd_tracker* tr, const blvd_odometry* odo) {
  if (!tr) return BLVD_ERR_MISUSE;
  if (!odo) return BLVD_ERR_INVALID_ARG;
  return feedGuarded([&] { tr->tracker->feedOdometry(blvd::capi::toTrack(*odo)); });
}

blvd_status blvd_tracker_feed_can_frame(blvd_tracker* tr, blvd_can_profile* profile, const blvd_can_frame* frame) {
  if (!tr || !profile) return BLVD_ERR_MISUSE;
  if (!frame) return BLVD_ERR_INVALID_ARG;
  blvd_odometry odo{};
  odo.struct_size = sizeof odo;
  const blvd_status st = blvd_can_profile_decode(profile, frame, &odo);
  if (st == BLVD_ERR_NOT_FOUND) return BLVD_OK;  // nothing for the profile on this frame
  if (st != BLVD_OK) return st;
  return blvd_tracker_feed_odometry(tr, &odo);
}

blvd_status blvd_tracker_get_pose(blvd_tracker* tr, double t, blvd_pose* pose) {
  if (!tr) return BLVD_ERR_MISUSE;
  if (!pose) return BLVD_ERR_INVALID_ARG;
  return trackerGuarded(tr, [&] {
    if (!std::isfinite(t)) throw core::Error(core::Status::InvalidArg, "blvd_tracker_get_pose: t is not finite");
    track::Pose p = tr->tracker->update(t);
    // On terrain (ELEV) the camera stands on the road, as the runtime's does.
    if (tr->city && (p.flags & track::kPoseMatched))
      tr->city->cameraOnRoad(p.cell, p.arc_m, tr->eye_height_m, p.camera.eye_u, p.camera.pitch_deg);
    blvd::capi::toBlvd(p, tr->frame, pose);
  });
}

blvd_status blvd_tracker_get_odometry_calibration(blvd_tracker* tr, blvd_odometry_calibration* cal) {
  if (!tr) return BLVD_ERR_MISUSE;
  if (!cal) return BLVD_ERR_INVALID_ARG;
  return trackerGuarded(tr, [&] { blvd::capi::toBlvd(tr->tracker->calibration(), cal); });
}

blvd_status blvd_tracker_set_odometry_calibration(blvd_tracker* tr, const blvd_odometry_calibration* cal) {
  if (!tr) return BLVD_ERR_MISUSE;
  if (!cal) return BLVD_ERR_INVALID_ARG;
  return trackerGuarded(tr, [&] { setCalibration(*tr->tracker, "blvd_tracker_set_odometry_calibration", *cal); });
}

blvd_status blvd_tracker_set_start_pose(blvd_tracker* tr, const blvd_start_pose* sp) {
  if (!tr) return BLVD_ERR_MISUSE;
  if (!sp) return BLVD_ERR_INVALID_ARG;
  return trackerGuarded(tr, [&] {
    setStartPose("blvd_tracker_set_start_pose", *sp,
                 [&](const track::StartPose& s) { return tr->tracker->setStartPose(s); });
  });
}

blvd_status blvd_tracker_get_stats(blvd_tracker* tr, blvd_tracking_stats* stats) {
  if (!tr) return BLVD_ERR_MISUSE;
  if (!stats) return BLVD_ERR_INVALID_ARG;
  return trackerGuarded(tr, [&] { blvd::capi::toBlvd(tr->tracker->stats(), stats); });
}

}  // extern "C"
