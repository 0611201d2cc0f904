// Tracking without GL through the public C API's tracker (blvd_tracker_*): on
// the package's street graph when a package is given, else on no graph at all
// (fusion and dead reckoning only) in a local frame at TrackingDesc's origin.
// libblvd opens no GL library for it, so a track-only host (the qemu guest of
// tests/vcan, an ECU without a GPU) runs it.
#include <memory>

#include "tracking.h"

namespace vcan_drive {
namespace {

class TrackerTracking final : public Tracking {
 public:
  explicit TrackerTracking(blvd_tracker* tr) : tr_(tr) {}
  ~TrackerTracking() override { blvd_tracker_destroy(tr_); }
  TrackerTracking(const TrackerTracking&) = delete;
  TrackerTracking& operator=(const TrackerTracking&) = delete;

  const char* name() const override { return "tracker"; }
  blvd_status feedOdometry(const blvd_odometry& o) override { return blvd_tracker_feed_odometry(tr_, &o); }
  blvd_status feedGnss(const blvd_gnss_fix& f) override { return blvd_tracker_feed_gnss(tr_, &f); }
  blvd_status getPose(double t, blvd_pose& r) override {
    r = blvd_pose{};
    r.struct_size = sizeof r;
    return blvd_tracker_get_pose(tr_, t, &r);
  }
  blvd_status getCalibration(blvd_odometry_calibration& out) override {
    out.struct_size = sizeof out;
    return blvd_tracker_get_odometry_calibration(tr_, &out);
  }
  blvd_status setCalibration(const blvd_odometry_calibration& in) override {
    return blvd_tracker_set_odometry_calibration(tr_, &in);
  }
  blvd_status setStartPose(const blvd_start_pose& in) override { return blvd_tracker_set_start_pose(tr_, &in); }
  std::string lastError() const override { return blvd_tracker_last_error(tr_); }

 private:
  blvd_tracker* tr_;
};

}  // namespace

std::unique_ptr<Tracking> makeTrackerTracking(const TrackingDesc& desc, std::string& err) {
  blvd_tracker_desc d{};
  d.struct_size = sizeof d;
  d.package_path = desc.package.empty() ? nullptr : desc.package.c_str();
  d.origin_lat = desc.origin_lat;
  d.origin_lon = desc.origin_lon;
  blvd_tracker* tr = nullptr;
  if (blvd_tracker_create(&d, &tr) != BLVD_OK) {
    err = blvd_tracker_last_error(nullptr);
    return nullptr;
  }
  return std::make_unique<TrackerTracking>(tr);
}

}  // namespace vcan_drive
