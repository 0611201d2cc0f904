// The tracking pipeline of the runtime (DESIGN.md, "track/"): GNSS fixes and
// odometry in, matched pose out.
//
//   feedGnss / feedOdometry   any thread: copy into a fixed ring (mutex, no allocation)
//   update(t)                 the tracking thread (the render thread in the runtime):
//                             drain the ring in time order -> GNSS to the local frame
//                             (GeographicLib, geo::LocalFrame) -> EKF (ekf.h) -> an HMM
//                             step per fix, or per match interval in an outage
//                             (map_matcher.h) -> map aid back into the EKF when the
//                             match is confident and the fixes agree -> the pose at t
//                             (the filter extrapolated to t, followed along the graph
//                             from the last match)
//   pose()                    the last update's result
//   setStartPose(sp)          key-on: start from the pose kept at the last key-off
//                             (a matched pose before the first fix)
//
// Lifecycle:
//   blvd::track::Tracker tr(city.frame(), &city.graph(), desc);  // allocates everything
//   // producer threads:
//   tr.feedGnss(fix);  tr.feedOdometry(odo);
//   // tracking thread, e.g. once per frame:
//   const blvd::track::Pose& p = tr.update(now);
//
// Contract:
// - Threads: feedGnss / feedOdometry may be called from any thread, concurrently
//   with each other and with update(). update(), pose(), reset(), stats() and
//   the accessors belong to one thread at a time.
// - Memory: the constructor allocates the ring, the filter, the matcher's
//   spatial index and every scratch buffer; nothing allocates afterwards
//   (checked by tests/track: zero operator new per feed and per update).
//   bytes() reports what was allocated.
// - Ordering: events drained by one update() are processed in timestamp order
//   (ties in feed order). An event older than the filter's time is "late": a
//   late fix is compared with the state moved back along the velocity, a late
//   odometry sample is applied as if current. Events are never dropped for
//   being late; a full ring drops its oldest event and the feed returns false.
//   An event kClockStepS or more older than the filter means the host's clock
//   went back, one kMaxGapS or more newer a gap no prediction spans: the drive
//   goes on from the filter's pose under the new time (counted in clock_steps).
//   A second report of a fix's epoch (same stamp) does not count its position
//   twice (gnss_duplicates).
// - Determinism: the same sequence of feed and update calls gives the same
//   poses, bit for bit (no clocks, no randomness, no hashing).
// - Errors: bad input never throws: a fix without a position, a NaN or an
//   out-of-range value is counted and ignored (a fix vaguer than 10 km, a
//   speed past 1 km/s, an angle past 720 degrees: tracker.cpp kMax*).
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include "geo/local_frame.h"
#include "graph/street_graph.h"
#include "track/ekf.h"
#include "track/map_matcher.h"
#include "track/types.h"

namespace blvd::track {

// An event this much older than the filter is not late but stamped by a clock
// that went back (no receiver or bus delivers data half a minute late); one
// this much newer comes after a gap no filter predicts across (the car parked
// with its bus asleep, or a clock that jumped ahead).
constexpr double kClockStepS = 30;
constexpr double kMaxGapS = 600;
// Fix stamps closer than this are one epoch (receivers report at 20 Hz at most).
constexpr double kSameEpochS = 1e-3;

// Zero means "default" for every field (see trackerDefaults()).
struct TrackerDesc {
  uint32_t ring_capacity = 0;   // events buffered between two update() calls; default 512
  double gnss_latency_s = 0;    // a fix is taken as valid at GnssFix::t - gnss_latency_s; default 0
  double match_interval_s = 0;  // HMM step period without GNSS (dead reckoning); default 1
  double outage_s = 0;          // no accepted fix for this long sets kPoseDeadReckoning; default 2.5
  double max_extrapolate_s = 0; // the pose is predicted at most this far past the last input; default 1
  double eye_height_m = 0;      // camera height above the street; default 1.5
  double camera_pitch_deg = 0;  // camera pitch, up positive (0 is level)
  // Map aiding: after an HMM step whose head has at least this posterior, the
  // filter is told the vehicle is on that street (a cross-track measurement of
  // sigma map_aid_sigma_m about the lane), provided the last fixes agree with
  // that street (their mean lateral offset) and that mean cannot also be the
  // lane of a parallel street alongside (ambiguity_sigmas); a lock onto the
  // wrong street would otherwise feed itself. Default 0.9 and 0.5 m; map_aid_sigma_m < 0 turns it off.
  // The sigma: vehicles keep within their lane with a lateral standard deviation
  // (SDLP) of 0.2-0.3 m, correlated over a few seconds of driving; applied once
  // per HMM step (1 Hz) as if independent, the constraint is counted about
  // tau x 1 Hz times within one correlation time tau ~ 4 s, so its sigma is
  // SDLP x sqrt(tau x 1 Hz) = 0.25 m x 2 = 0.5 m (the simulator, sim.h, drives
  // with this wander: SimDesc::lane_wander_m, lane_wander_length_m).
  double map_aid_min_confidence = 0;
  double map_aid_sigma_m = 0;
  // Where vehicles drive on a two-way street: this far right of the centre line
  // (the map aid's expected offset; one-way streets: the centre). Default 1.75 m.
  double lane_offset_m = 0;
  bool left_hand_traffic = false;  // the offset is to the left
  // No map aid while the fixes' mean offset (the agreement check's) lies within
  // this many of its sigmas of where it would be in the lane of another street
  // running alongside (the fixes cannot yet tell which one the vehicle is on);
  // default 2.5.
  double ambiguity_sigmas = 0;
  EkfDesc ekf;
  MatcherDesc matcher;
};

TrackerDesc trackerDefaults(const TrackerDesc& desc);

struct TrackerStats {
  uint64_t gnss_fed = 0, odometry_fed = 0;
  uint64_t ring_dropped = 0;     // events lost to a full ring
  uint32_t ring_high_water = 0;  // most events waiting at once
  uint64_t gnss_used = 0, gnss_rejected = 0;  // position updates accepted / gated out
  uint64_t gnss_ignored = 0;     // no position, no fix, or not finite
  uint64_t odometry_ignored = 0; // not finite
  uint64_t late_events = 0;      // older than the filter when processed
  // Reports of an epoch already processed (the same time stamp: gpsd's TPV per
  // sentence, an NMEA epoch completed late, a fix fed twice): the position
  // counts once; a speed or course the first report lacked is still used.
  uint64_t gnss_duplicates = 0;
  uint64_t outages = 0;          // times dead reckoning began after an accepted fix (TrackerDesc::outage_s)
  double longest_outage_s = 0;   // the longest time without an accepted fix, once past outage_s
  uint64_t clock_steps = 0;      // events kClockStepS or more before the filter or kMaxGapS after it
  uint64_t filter_resets = 0;    // position resets after a run of rejected fixes
  uint64_t map_aids = 0, map_aids_rejected = 0;  // street constraints applied / gated out
  uint64_t map_aid_suspensions = 0;  // times the fixes stopped agreeing with the matched street
  // HMM steps without a map aid, by the first reason: head below the confidence
  // floor, fixes not (yet) agreeing with the street, another street alongside.
  uint64_t map_aid_low_confidence = 0, map_aid_disagreeing = 0, map_aid_ambiguous = 0;
  MatchStats match;
};

class Tracker {
 public:
  // `graph` may be null (fusion only, no map matching); it must outlive the
  // tracker. The frame is copied.
  Tracker(const geo::LocalFrame& frame, const graph::StreetGraph* graph, const TrackerDesc& desc = TrackerDesc{});
  // Over any graph source (a package's paged graph, stream::City::streets()).
  Tracker(const geo::LocalFrame& frame, const graph::GraphSource* graph, const TrackerDesc& desc = TrackerDesc{});
  Tracker(const geo::LocalFrame& frame, std::nullptr_t, const TrackerDesc& desc = TrackerDesc{})
      : Tracker(frame, static_cast<const graph::GraphSource*>(nullptr), desc) {}
  ~Tracker();
  Tracker(const Tracker&) = delete;
  Tracker& operator=(const Tracker&) = delete;

  // Any thread. False when the ring was full and its oldest event was dropped
  // to make room (this event is kept).
  bool feedGnss(const GnssFix& fix);
  bool feedOdometry(const Odometry& odo);

  // Tracking thread: processes what was fed and returns the pose at time t.
  const Pose& update(double t);
  const Pose& pose() const { return pose_; }

  // Tracking thread: forgets the filter, the match and anything still in the ring
  // (not the odometry calibration given to setCalibration).
  void reset();

  // Tracking thread: starts the drive from a known pose (types.h StartPose: the
  // pose kept from the end of the previous drive) instead of waiting for the
  // first fix: the filter starts there (sigmas raised to the floors) and the
  // matcher takes one step from it, so update() gives a matched pose at once,
  // dead reckoning until a fix arrives. A drive under way is forgotten first
  // (as reset(), except for the events still in the ring). Fixes that disagree
  // with the start pose (the car was moved while parked) are gated out and,
  // after EkfDesc::reset_after_rejects of them, reset the position to theirs.
  // False, changing nothing, for a non-finite or out-of-range field, a
  // negative sigma, a position sigma over 10 km or a heading sigma over 180
  // degrees, a heading beyond 720 degrees.
  bool setStartPose(const StartPose& sp);

  // Tracking thread: the odometry calibration learned so far (ekf.h), to keep
  // for the vehicle's next drive, and the one to start from (Ekf::setCalibration).
  OdometryCalibration calibration() const { return ekf_.calibration(); }
  bool setCalibration(const OdometryCalibration& c) { return ekf_.setCalibration(c); }

  TrackerStats stats() const;
  const TrackerDesc& desc() const { return d_; }
  const Ekf& filter() const { return ekf_; }
  const MapMatcher* matcher() const { return matcher_.get(); }
  // Bytes allocated by the constructor (ring, matcher, index, scratch).
  size_t bytes() const;

 private:
  struct Event {
    double t = 0;
    uint64_t seq = 0;
    bool is_gnss = false;
    GnssFix gnss;
    Odometry odo;
  };

  bool push(const Event& ev);
  // The clock went back (an event kClockStepS or more older than the filter)
  // or a gap no prediction spans (kMaxGapS or more newer): the drive goes on
  // from the filter's pose under the new time.
  bool clockStepped(double t);
  // Flags dead reckoning on the pose and counts outages.
  void noteOutage(Pose& p);
  // Forgets the drive: filter, match, map aid, times (not the ring, not the stats).
  void forgetDrive();
  void processGnss(const GnssFix& f, double t);
  // advance: move the filter to o.t after applying o (false while more samples of the same stamp follow).
  void processOdometry(const Odometry& o, bool advance);
  // heading_at_rest: the filter's heading counts below walking speed too (a
  // stored start pose's, not a course from GNSS).
  void matchStep(const double* fix_en = nullptr, double fix_sigma = 0, bool heading_at_rest = false);
  // The fixes' side of the matched street: suspends the map aid when they disagree.
  void checkStreetAgreement(double e, double n, double sigma);
  double expectedOffset(uint32_t cell) const;
  // The map aid's expected offset and sigma through a corner (tracker.cpp).
  void cornerShift(double& offset, double& sigma) const;
  bool ambiguous() const;

  TrackerDesc d_;
  geo::LocalFrame frame_;
  const graph::GraphSource* graph_ = nullptr;  // the matcher's: null without one
  std::unique_ptr<MapMatcher> matcher_;
  Ekf ekf_;

  // Feed side (guarded by mu_).
  mutable std::mutex mu_;
  std::vector<Event> ring_;
  size_t ring_head_ = 0, ring_count_ = 0;
  uint64_t seq_ = 0, gnss_fed_ = 0, odo_fed_ = 0, dropped_ = 0;
  uint32_t high_water_ = 0;

  // Tracking side.
  std::vector<Event> batch_;
  Pose pose_;
  CellPoint cur_;            // the match, followed between HMM steps
  double confidence_ = 0;
  double lateral_mean_ = 0;     // mean of the fixes' offset from the expected lane
  double lateral_mean_var_ = 0; // its variance
  uint32_t agreement_fixes_ = 0;
  bool street_agrees_ = false;  // the map aid is on
  double last_step_t_ = -1e300, last_fix_t_ = -1e300, last_fix_event_t_ = -1e300;
  double last_gyro_t_ = -1e300, last_odo_speed_t_ = -1e300;
  uint32_t epoch_parts_ = 0;    // what the last fix event's epoch has given (tracker.cpp EpochPart)
  bool in_outage_ = false;
  uint64_t carried_resets_ = 0; // filter resets before the last clock step
  TrackerStats st_;
};

}  // namespace blvd::track
