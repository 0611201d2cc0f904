// Tracking in the runtime: the feeds, the tracked pose, and which cell the
// camera is on (the tracker's matched cell, or CellChoice for a host pose).
#include <cmath>

#include "runtime/runtime.h"

namespace blvd::runtime {

// The newest fed time, from any feeding thread: a compare-and-swap maximum,
// so that two feeds racing cannot move it backwards.
void Runtime::noteFeed(double t) {
  double seen = last_feed_t_.load();
  while (t > seen && !last_feed_t_.compare_exchange_weak(seen, t)) {
  }
}

void Runtime::feedGnss(const track::GnssFix& fix) {
  tracker_->feedGnss(fix);
  noteFeed(fix.t);
}

void Runtime::feedOdometry(const track::Odometry& odo) {
  tracker_->feedOdometry(odo);
  noteFeed(odo.t);
}

const track::Pose& Runtime::pose(double t) {
  if (!std::isfinite(t)) throw core::Error(core::Status::InvalidArg, "blvd_get_pose: t is not finite");
  posed_ = tracker_->update(t);
  if (posed_.flags & track::kPoseMatched)
    onRoad(posed_.cell, posed_.arc_m, posed_.camera.pitch_deg, posed_.camera.eye_u, posed_.camera.pitch_deg);
  return posed_;
}

bool Runtime::setStartPose(const track::StartPose& sp) {
  if (!tracker_->setStartPose(sp)) return false;
  // The tracked camera stands there, at the start pose's time until something is fed.
  noteFeed(sp.t);
  return true;
}

uint32_t Runtime::currentCell(double& arc_m, double& speed) {
  uint32_t cell = graph::kNone;
  arc_m = speed = 0;
  off_map_ = false;
  if (camera_source_ == BLVD_CAMERA_TRACKED) {
    // Tracking drives the camera: the pose at the newest fed time.
    const track::Pose& p = tracker_->update(last_feed_t_.load());
    if (p.flags & track::kPoseValid) {
      cam_.eye_enu = {p.camera.eye_e, p.camera.eye_n, p.camera.eye_u};
      cam_.heading_deg = p.camera.heading_deg;
      cam_.pitch_deg = pose_pitch_deg_ = p.camera.pitch_deg;
      speed = p.speed_mps;
      host_off_map_ = false;  // the host's pose is no longer where the camera is
      off_map_ = (p.flags & track::kPoseOffMap) != 0;
      if (p.flags & track::kPoseMatched) cell = p.cell, arc_m = p.arc_m;
    }
  }
  off_map_ = off_map_ || host_off_map_;
  if (off_map_) {  // never the nearest cell: it may be hundreds of kilometres away
    choice_->forget();
    return graph::kNone;
  }
  if (cell != graph::kNone) {
    choice_->forget();
    return cell;
  }
  return choice_->choose(glm::dvec2(cam_.eye_enu.x, cam_.eye_enu.y), cam_.heading_deg, arc_m);
}

}  // namespace blvd::runtime
