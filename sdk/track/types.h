// What the tracking module takes in and gives out: GNSS fixes, odometry
// samples, and the matched pose.
//
// The input structs mirror the adapters' types field for field (adapters/gnss
// fix.h `gnss::Fix`, adapters/can profile.h `can::Odometry`), with the same flag
// bit values, so sdk/capi can copy a `blvd_gnss_fix` / `blvd_odometry` member by
// member. They are plain types: no pointers, no allocation, safe to copy into a
// ring buffer.
//
// Clock: every `t` here (GnssFix::t, Odometry::t, Tracker::update(t)) is on one
// clock chosen by the host, in seconds; only differences matter. A GNSS fix is
// stamped with the time it was valid on that clock (see TrackerDesc::gnss_latency_s
// for receivers that are stamped on arrival).
#pragma once
#include <cstdint>

namespace blvd::track {

inline constexpr uint32_t kNoCell = 0xffffffffu;  // == graph::kNone

// Bits of GnssFix::flags: the same values as gnss::FixFlag.
enum GnssFlag : uint32_t {
  kGnssHasTime = 1u << 0,
  kGnssHasLatLon = 1u << 1,
  kGnssHasAlt = 1u << 2,
  kGnssHasSpeed = 1u << 3,  // speed_mps
  kGnssHasTrack = 1u << 4,  // track_deg
  kGnssHasHdop = 1u << 5,   // hdop
  kGnssHasHAcc = 1u << 6,   // h_acc_m (GST)
};

// GnssFix::mode: the same values as gnss::FixMode.
enum GnssMode : int { kGnssModeUnknown = 0, kGnssModeNoFix = 1, kGnssMode2D = 2, kGnssMode3D = 3 };

struct GnssFix {
  double t = 0;          // tracker clock, seconds: when the position was valid
  double lat = 0;        // degrees, WGS 84
  double lon = 0;
  double alt = 0;        // metres above mean sea level (unused by the 2D filter)
  float speed_mps = 0;   // over ground
  float track_deg = 0;   // course over ground, degrees true
  float hdop = 0;
  float h_acc_m = 0;     // sqrt(lat_err^2 + lon_err^2) from GST: per-axis sigma = h_acc_m / sqrt(2)
  int mode = kGnssModeUnknown;  // a kGnssModeNoFix fix is counted and ignored
  uint32_t flags = 0;    // GnssFlag bits; a field whose bit is clear is ignored
};

// Bits of Odometry::flags. The low ones are the values of can::OdometryField.
enum OdometryFlag : uint32_t {
  kOdoSpeed = 1u << 0,        // speed_mps: ground speed (wheel mean or vehicle signal)
  kOdoYawRate = 1u << 2,      // yaw_rate_dps
  kOdoWheelSpeeds = 1u << 4,  // wheel_speeds_mps, all four
  kOdoGear = 1u << 5,         // reverse
  kOdoHeading = 1u << 8,      // heading_deg: an absolute heading (compass, dual antenna, simulator)
};

struct Odometry {
  double t = 0;                     // tracker clock, seconds
  double speed_mps = 0;             // unsigned; reverse says which way
  double yaw_rate_dps = 0;          // positive to the left (counterclockwise from above, ISO 8855)
  double wheel_speeds_mps[4] = {};  // front left, front right, rear left, rear right
  double heading_deg = 0;           // clockwise from north
  bool reverse = false;             // gear is reverse (with kOdoGear)
  uint32_t flags = 0;               // OdometryFlag bits: the fields this sample carries
};

// Where the vehicle was last known to be, to start a drive from
// (Tracker::setStartPose): typically the pose read at the end of the previous
// drive (key-off) and kept in non-volatile memory, as automotive navigation
// keeps its last position so that it knows where it is at the next start,
// before the first fix and in a garage without one (Groves, 2nd ed., §16.3.4).
// Stored as latitude and longitude, so it outlives a package update.
struct StartPose {
  double t = 0;                  // tracker clock, seconds: when the vehicle was (still) there
  double lat = 0, lon = 0;       // degrees, WGS 84
  double heading_deg = 0;        // clockwise from north
  double sigma_m = 0;            // per-axis 1-sigma of the position; 0: kStartSigmaDefaultM
  double heading_sigma_deg = 0;  // 0: kStartHeadingSigmaDefaultDeg
};

// StartPose sigmas: the defaults when the host gives none, and the floors a
// given one is raised to (a parked car is rarely where its last fused pose put
// it to better than half a metre: the pose's own error, the last metres of
// parking).
inline constexpr double kStartSigmaDefaultM = 2.0, kStartSigmaMinM = 0.5;
inline constexpr double kStartHeadingSigmaDefaultDeg = 5.0, kStartHeadingSigmaMinDeg = 1.0;

// A camera placement for rendering, in the package's local frame (east, north,
// up metres); maps onto render::Camera's eye_enu / heading_deg / pitch_deg.
struct CameraPose {
  double eye_e = 0, eye_n = 0, eye_u = 0;
  double heading_deg = 0;  // clockwise from north
  double pitch_deg = 0;
};

// Bits of Pose::flags.
enum PoseFlag : uint32_t {
  kPoseValid = 1u << 0,          // position and heading hold an estimate
  kPoseHeadingValid = 1u << 1,   // heading has been observed (GNSS track, motion, or an absolute heading)
  kPoseMatched = 1u << 2,        // cell / arc_m / lateral_m hold a map match
  kPoseDeadReckoning = 1u << 3,  // no GNSS fix accepted for TrackerDesc::outage_s
  kPoseOffMap = 1u << 4,         // the fused position is off the map (graph::onMap): no cell, no match
};

struct Pose {
  double t = 0;                 // the time update() was asked for
  uint32_t cell = kNoCell;      // matched half-edge (graph cell)
  double arc_m = 0;             // along the cell's polyline from its origin
  double lateral_m = 0;         // signed distance from the cell's polyline, positive to its right
  double heading_deg = 0;       // fused vehicle heading, clockwise from north
  double confidence = 0;        // posterior probability of `cell` in the HMM's filter, [0, 1]
  double e = 0, n = 0;          // fused position, local frame metres
  double speed_mps = 0;         // fused speed
  double pos_sigma_m = 0;       // 1-sigma of the fused position (largest axis)
  double heading_sigma_deg = 0; // 1-sigma of the fused heading (0 until the heading is valid)
  uint32_t settled_cell = kNoCell;  // the fixed-lag Viterbi decision for the step at settled_t
  double settled_t = 0;
  CameraPose camera;            // eye on the matched street (or at the fused position when unmatched)
  uint32_t flags = 0;           // PoseFlag bits
};

}  // namespace blvd::track
