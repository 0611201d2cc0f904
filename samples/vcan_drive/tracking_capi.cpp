// Tracking through the public C API: a blvd_runtime that tracks and renders,
// fed CAN frames through a blvd_can_profile (blvd_feed_can_frame).
#include <cstring>

#include "tracking.h"

namespace vcan_drive {
namespace {

class CapiTracking final : public Tracking {
 public:
  CapiTracking(blvd_runtime* rt, blvd_can_profile* profile, const blvd_runtime_desc& d)
      : rt_(rt), profile_(profile), width_(d.width), height_(d.height) {}
  ~CapiTracking() override {
    blvd_can_profile_destroy(profile_);
    blvd_runtime_destroy(rt_);
  }

  const char* name() const override { return "capi"; }
  blvd_status feedOdometry(const blvd_odometry& odo) override { return blvd_feed_odometry(rt_, &odo); }
  bool feedsCanFrames() const override { return true; }
  blvd_status feedCanFrame(const blvd_can_frame& frame) override { return blvd_feed_can_frame(rt_, profile_, &frame); }
  blvd_status feedGnss(const blvd_gnss_fix& fix) override { return blvd_feed_gnss(rt_, &fix); }
  blvd_status getPose(double t, blvd_pose& out) override {
    out.struct_size = sizeof out;
    return blvd_get_pose(rt_, t, &out);
  }
  blvd_status getCalibration(blvd_odometry_calibration& out) override {
    out.struct_size = sizeof out;
    return blvd_get_odometry_calibration(rt_, &out);
  }
  blvd_status setCalibration(const blvd_odometry_calibration& in) override {
    return blvd_set_odometry_calibration(rt_, &in);
  }
  blvd_status setStartPose(const blvd_start_pose& in) override { return blvd_set_start_pose(rt_, &in); }

  bool canRender() const override { return true; }
  blvd_status render(const blvd_pose* pose, unsigned char* rgba, blvd_frame_stats& fs) override {
    blvd_status st = BLVD_OK;
    // A recorded pose places the eye where its camera was (on the matched
    // street); otherwise blvd_render follows the tracker.
    // Recorded poses are drawn offline: wait for the pose's cell, so a frame
    // never shows the previous cell's blocks around a camera that has moved
    // on (it may stand inside one of them).
    st = blvd_set_camera_source(rt_, pose ? BLVD_CAMERA_HOST : BLVD_CAMERA_TRACKED);
    if (st == BLVD_OK && pose) {
      st = blvd_set_pose_local(rt_, pose->camera_x, pose->camera_y, static_cast<float>(pose->camera_heading_deg),
                               static_cast<float>(pose->camera_pitch_deg));
      if (st == BLVD_OK) st = blvd_wait_resident(rt_, 30000);
    }
    if (st != BLVD_OK) return st;
    fs = blvd_frame_stats{};
    fs.struct_size = sizeof fs;
    if ((st = blvd_render(rt_, &fs)) != BLVD_OK) return st;
    return blvd_read_pixels(rt_, rgba, static_cast<size_t>(width_) * height_ * 4);
  }
  bool runtimeStats(blvd_stats& out) override {
    out = blvd_stats{};
    out.struct_size = sizeof out;
    return blvd_runtime_stats(rt_, &out) == BLVD_OK;
  }
  uint32_t width() const override { return width_; }
  uint32_t height() const override { return height_; }
  std::string lastError() const override { return blvd_last_error(rt_); }

 private:
  blvd_runtime* rt_;
  blvd_can_profile* profile_;
  uint32_t width_, height_;
};

}  // namespace

std::unique_ptr<Tracking> makeCapiTracking(const TrackingDesc& desc, std::string& err) {
  if (desc.package.empty()) {
    err = "the C API needs a package (--package)";
    return nullptr;
  }
  blvd_runtime_desc d{};
  d.struct_size = sizeof d;
  d.package_path = desc.package.c_str();
  d.width = desc.width;
  d.height = desc.height;
  d.backend = desc.backend;
  d = blvd_runtime_desc_defaults(&d);
  blvd_can_profile_desc pd{};
  pd.struct_size = sizeof pd;
  pd.vehicle = desc.vehicle;
  pd.dbc_path = desc.dbc_path.c_str();
  blvd_can_profile* profile = nullptr;
  if (blvd_can_profile_create(&pd, &profile) != BLVD_OK) {
    err = blvd_last_error(nullptr);
    return nullptr;
  }
  blvd_runtime* rt = nullptr;
  if (blvd_runtime_create(&d, &rt) != BLVD_OK) {
    err = blvd_last_error(nullptr);
    blvd_can_profile_destroy(profile);
    return nullptr;
  }
  return std::make_unique<CapiTracking>(rt, profile, d);
}

}  // namespace vcan_drive
