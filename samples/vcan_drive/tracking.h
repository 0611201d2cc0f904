// The tracker vcan_drive feeds, behind one small interface so the program does
// not care which implementation it has:
//
//   makeCapiTracking()     a blvd_runtime on a package, with a GL backend;
//                          tracks and renders (tracking_capi.cpp).
//   makeTrackerTracking()  a blvd_tracker: the package's street graph when one
//                          is given, no GL (tracking_tracker.cpp), for a
//                          track-only host (the qemu guest of tests/vcan, an
//                          ECU without a GPU).
// Both are the public C API: the same feeds give the same poses.
#pragma once

#include <memory>
#include <string>

#include "blvd/blvd.h"

namespace vcan_drive {

class Tracking {
 public:
  virtual ~Tracking() = default;
  virtual const char* name() const = 0;  // "capi" or "tracker"
  virtual blvd_status feedOdometry(const blvd_odometry& odo) = 0;
  // The runtime implementation decodes CAN frames itself (blvd_feed_can_frame
  // with the DBC and vehicle of TrackingDesc); the tracker one is fed odometry.
  virtual bool feedsCanFrames() const { return false; }
  virtual blvd_status feedCanFrame(const blvd_can_frame& frame) {
    (void)frame;
    return BLVD_ERR_UNSUPPORTED;
  }
  virtual blvd_status feedGnss(const blvd_gnss_fix& fix) = 0;
  virtual blvd_status getPose(double t, blvd_pose& out) = 0;
  // The odometry calibration (blvd_get/set_odometry_calibration): kept between drives.
  virtual blvd_status getCalibration(blvd_odometry_calibration& out) = 0;
  virtual blvd_status setCalibration(const blvd_odometry_calibration& in) = 0;
  // Tracking from a known pose before the first fix (blvd_set_start_pose).
  virtual blvd_status setStartPose(const blvd_start_pose& in) = 0;

  // Rendering; only the C API implementation can.
  virtual bool canRender() const { return false; }
  // Renders at the tracked pose (or at `pose` when given) and copies the
  // frame into rgba (width*height*4); `fs` is blvd_render's frame stats.
  virtual blvd_status render(const blvd_pose* pose, unsigned char* rgba, blvd_frame_stats& fs) {
    (void)pose, (void)rgba, (void)fs;
    return BLVD_ERR_UNSUPPORTED;
  }
  // blvd_runtime_stats (residency, pools, tracking memory); false without a runtime.
  virtual bool runtimeStats(blvd_stats& out) {
    (void)out;
    return false;
  }
  virtual uint32_t width() const { return 0; }
  virtual uint32_t height() const { return 0; }
  // Text about the last failure.
  virtual std::string lastError() const = 0;
};

struct TrackingDesc {
  std::string package;      // .blvd; empty: none (tracker only, no map matching)
  uint32_t width = 800, height = 480;
  blvd_backend backend = BLVD_BACKEND_AUTO;
  double origin_lat = 0, origin_lon = 0;  // the local frame without a package
  std::string dbc_path;                    // CAN decoding of the C API implementation
  blvd_vehicle vehicle = BLVD_VEHICLE_TOYOTA;
};

// Null with `err` set on failure.
std::unique_ptr<Tracking> makeCapiTracking(const TrackingDesc& desc, std::string& err);
std::unique_ptr<Tracking> makeTrackerTracking(const TrackingDesc& desc, std::string& err);

}  // namespace vcan_drive
