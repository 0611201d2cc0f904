// The tracker vcan_drive feeds, behind one small interface so the program does
// not care which implementation it has:
//
//   makeCapiTracking()    the public C API: a blvd_runtime on a package, with a
//                         GL backend; tracks and renders (tracking_capi.cpp).
//   makeDirectTracking()  sdk/track's Tracker, with the package's street graph
//                         when one is given, and no GL (tracking_direct.cpp).
//
// The second exists only because blvd_runtime_create() needs both a package and
// a GL context, so a track-only host (the qemu guest of tests/vcan, an ECU
// without a GPU) cannot use the C API today. Its inputs and outputs are the C
// API's own structs, so when the C API gains a track-only runtime it is replaced
// by makeCapiTracking() without touching the rest of the program.
#pragma once

#include <memory>
#include <string>

#include "blvd/blvd.h"

namespace vcan_drive {

class Tracking {
 public:
  virtual ~Tracking() = default;
  virtual const char* name() const = 0;  // "capi" or "direct"
  virtual blvd_status feedOdometry(const blvd_odometry& odo) = 0;
  // The C API implementation decodes CAN frames itself (blvd_feed_can_frame
  // with the DBC and vehicle of TrackingDesc); the direct one is fed odometry.
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
  // Package origin (degrees); 0, 0 when there is none.
  virtual void origin(double& lat, double& lon) const = 0;

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
  std::string package;      // .blvd; empty: none (direct tracking only)
  uint32_t width = 800, height = 480;
  blvd_backend backend = BLVD_BACKEND_AUTO;
  double origin_lat = 0, origin_lon = 0;  // the local frame without a package
  std::string dbc_path;                    // CAN decoding of the C API implementation
  blvd_vehicle vehicle = BLVD_VEHICLE_TOYOTA;
};

// Null with `err` set on failure.
std::unique_ptr<Tracking> makeCapiTracking(const TrackingDesc& desc, std::string& err);
std::unique_ptr<Tracking> makeDirectTracking(const TrackingDesc& desc, std::string& err);

}  // namespace vcan_drive
