// The C API's tracking inputs as sdk/track's structs, and a tracked pose as
// the C API's (toBlvd). Used by the runtime's
// feeds and by `blvd bench track`, which tracks what the adapters produce for a
// host (blvd_gnss_fix / blvd_odometry) without a runtime. The flag bits are the
// same values (checked below at compile time).
#pragma once

#include <algorithm>
#include <cstring>

#include "blvd/blvd.h"
#include "core/math.h"
#include "core/sized.h"
#include "geo/local_frame.h"
#include "track/ekf.h"
#include "track/types.h"

namespace blvd::capi {

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
                  BLVD_POSE_HEADING_VALID == track::kPoseHeadingValid && BLVD_POSE_OFF_MAP == track::kPoseOffMap,
              "pose flag bits");

inline track::GnssFix toTrack(const blvd_gnss_fix& in) {
  const blvd_gnss_fix f = core::sized(in);
  track::GnssFix g;
  g.t = f.t;
  g.lat = f.lat;
  g.lon = f.lon;
  g.alt = f.alt;
  g.speed_mps = f.speed_mps;
  g.track_deg = f.track_deg;
  g.hdop = f.hdop;
  g.h_acc_m = f.h_acc_m;
  g.mode = core::rawEnum(f.mode);
  g.flags = f.flags;  // BLVD_GNSS_HAS_* == track::GnssFlag bits
  return g;
}

inline track::Odometry toTrack(const blvd_odometry& in) {
  const blvd_odometry o = core::sized(in);
  track::Odometry d;
  d.t = o.t;
  d.speed_mps = o.speed_mps;
  d.yaw_rate_dps = o.yaw_rate_dps;
  for (int i = 0; i < 4; ++i) d.wheel_speeds_mps[i] = o.wheel_speeds_mps[i];
  d.heading_deg = o.heading_deg;
  d.reverse = o.reverse != 0;
  d.flags = o.flags;  // BLVD_ODO_* == track::OdometryFlag bits
  return d;
}

// A tracked pose as the C API's blvd_pose, written up to out->struct_size
// bytes (0: the whole struct); lat/lon through the package's frame.
inline void toBlvd(const track::Pose& p, const geo::LocalFrame& frame, blvd_pose* out) {
  blvd_pose r{};
  r.struct_size = out->struct_size ? out->struct_size : sizeof r;
  r.t = p.t;
  r.x = p.e;
  r.y = p.n;
  double h = 0;
  frame.reverse({p.e, p.n, 0}, r.lat, r.lon, h);
  r.heading_deg = p.heading_deg;
  r.speed_mps = p.speed_mps;
  r.cell = p.cell;
  r.arc_m = p.arc_m;
  r.lateral_m = p.lateral_m;
  r.confidence = p.confidence;
  r.flags = p.flags;  // BLVD_POSE_* == track::PoseFlag bits
  r.camera_x = p.camera.eye_e;
  r.camera_y = p.camera.eye_n;
  r.camera_z = p.camera.eye_u;
  r.camera_heading_deg = p.camera.heading_deg;
  r.camera_pitch_deg = p.camera.pitch_deg;
  r.pos_sigma_m = p.pos_sigma_m;
  r.heading_sigma_deg = p.heading_sigma_deg;
  std::memcpy(out, &r, std::min<size_t>(r.struct_size, sizeof r));
}

inline track::StartPose toTrack(const blvd_start_pose& in) {
  track::StartPose s;
  s.t = in.t;
  s.lat = in.lat;
  s.lon = in.lon;
  s.heading_deg = in.heading_deg;
  s.sigma_m = in.sigma_m;
  s.heading_sigma_deg = in.heading_sigma_deg;
  return s;
}

// The odometry calibration: degrees per second in the C API, radians in sdk/track.
constexpr double kRadPerDeg = core::kDegToRad;

inline track::OdometryCalibration toTrack(const blvd_odometry_calibration& in) {
  track::OdometryCalibration c;
  c.speed_scale = in.speed_scale;
  c.speed_scale_sigma = in.speed_scale_sigma;
  c.yaw_bias_rad_s = in.yaw_rate_bias_dps * kRadPerDeg;
  c.yaw_bias_sigma_rad_s = in.yaw_rate_bias_sigma_dps * kRadPerDeg;
  return c;
}

// Writes min(out->struct_size, sizeof) bytes (all of it when struct_size is 0).
inline void toBlvd(const track::OdometryCalibration& c, blvd_odometry_calibration* out) {
  blvd_odometry_calibration r{};
  r.struct_size = out->struct_size && out->struct_size < sizeof r ? out->struct_size : sizeof r;
  r.speed_scale = c.speed_scale;
  r.speed_scale_sigma = c.speed_scale_sigma;
  r.yaw_rate_bias_dps = c.yaw_bias_rad_s / kRadPerDeg;
  r.yaw_rate_bias_sigma_dps = c.yaw_bias_sigma_rad_s / kRadPerDeg;
  std::memcpy(out, &r, r.struct_size);
}

// The tracker's statistics, written up to out->struct_size bytes (0: the whole struct).
inline void toBlvd(const track::TrackerStats& st, blvd_tracking_stats* out) {
  blvd_tracking_stats r{};
  r.struct_size = out->struct_size && out->struct_size < sizeof r ? out->struct_size : sizeof r;
  r.gnss_fed = st.gnss_fed;
  r.odometry_fed = st.odometry_fed;
  r.queue_dropped = st.ring_dropped;
  r.gnss_used = st.gnss_used;
  r.gnss_rejected = st.gnss_rejected;
  r.gnss_ignored = st.gnss_ignored;
  r.gnss_duplicates = st.gnss_duplicates;
  r.odometry_ignored = st.odometry_ignored;
  r.late = st.late_events;
  r.clock_steps = st.clock_steps;
  r.filter_resets = st.filter_resets;
  r.outages = st.outages;
  r.longest_outage_s = st.longest_outage_s;
  std::memcpy(out, &r, r.struct_size);
}

}  // namespace blvd::capi
