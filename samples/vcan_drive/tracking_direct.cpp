// Track-only tracking without GL: sdk/track's Tracker, on the package's street
// graph when a package is given (stream::City opens it without a GL context),
// else on no graph at all (fusion and dead reckoning only) in a local frame at
// TrackingDesc's origin. It converts the C API's structs with the runtime's own
// conversion (sdk/capi/track_convert.h, header-only), so its poses are the ones a track-only runtime
// would return (see tracking.h for why it exists).
#include <memory>
#include <stdexcept>

#include "capi/track_convert.h"
#include "stream/city.h"
#include "track/tracker.h"
#include "tracking.h"

namespace vcan_drive {
namespace {

using namespace blvd;

class DirectTracking final : public Tracking {
 public:
  // `city` may be null (no package).
  DirectTracking(std::unique_ptr<stream::City> city, const geo::LocalFrame& frame, double lat, double lon)
      : city_(std::move(city)),
        frame_(frame),
        tracker_(frame_, city_ ? &city_->graph() : nullptr),
        lat_(lat),
        lon_(lon) {}

  const char* name() const override { return "direct"; }

  blvd_status feedOdometry(const blvd_odometry& o) override {
    tracker_.feedOdometry(capi::toTrack(o));
    return BLVD_OK;
  }

  blvd_status feedGnss(const blvd_gnss_fix& f) override {
    tracker_.feedGnss(capi::toTrack(f));
    return BLVD_OK;
  }

  blvd_status getPose(double t, blvd_pose& r) override {
    r = blvd_pose{};
    capi::toBlvd(tracker_.update(t), frame_, &r);
    return BLVD_OK;
  }

  blvd_status getCalibration(blvd_odometry_calibration& out) override {
    out.struct_size = sizeof out;
    capi::toBlvd(tracker_.calibration(), &out);
    return BLVD_OK;
  }
  blvd_status setCalibration(const blvd_odometry_calibration& in) override {
    if (tracker_.setCalibration(capi::toTrack(in))) return BLVD_OK;
    error_ = "odometry calibration refused (scale outside [0.5, 2], bias beyond 10 deg/s or a bad sigma)";
    return BLVD_ERR_INVALID_ARG;
  }
  blvd_status setStartPose(const blvd_start_pose& in) override {
    if (tracker_.setStartPose(capi::toTrack(in))) return BLVD_OK;
    error_ = "start pose refused (a field not finite, lat/lon out of range or a negative sigma)";
    return BLVD_ERR_INVALID_ARG;
  }
  void origin(double& lat, double& lon) const override { lat = lat_, lon = lon_; }
  std::string lastError() const override { return error_; }

 private:
  std::unique_ptr<stream::City> city_;
  geo::LocalFrame frame_;
  track::Tracker tracker_;
  double lat_, lon_;
  std::string error_;
};

}  // namespace

std::unique_ptr<Tracking> makeDirectTracking(const TrackingDesc& desc, std::string& err) {
  try {
    if (desc.package.empty())
      return std::make_unique<DirectTracking>(nullptr, geo::LocalFrame(desc.origin_lat, desc.origin_lon),
                                              desc.origin_lat, desc.origin_lon);
    auto city = std::make_unique<stream::City>();
    if (city->open(desc.package, err) != core::Status::Ok) return nullptr;
    double lat = 0, lon = 0, h = 0;
    city->frame().reverse({0, 0, 0}, lat, lon, h);
    const geo::LocalFrame frame = city->frame();
    return std::make_unique<DirectTracking>(std::move(city), frame, lat, lon);
  } catch (const std::exception& e) {  // GeographicLib throws on a bad origin
    err = e.what();
    return nullptr;
  }
}

}  // namespace vcan_drive
