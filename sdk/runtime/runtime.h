// The object behind blvd_runtime*: a package's city, the GL context and
// renderer, the resident-cell slots, the draw list, the tracker and the
// camera. sdk/capi maps the C API onto it. Files, in the order a frame walks:
//   runtime.cpp      create (memory plan first, then every pool), settings, stats
//   tracking.cpp     feeds, the tracked pose, and which cell the camera is on
//   cell_slots.*     the slots' state machine, uploads (slot_upload.cpp), block reuse (block_copy.cpp)
//   draw_list.*      what to draw, levels of detail (lod_choice.cpp)
//   frame.cpp        one frame: stream, draw list, render (views), frame budget, read-back
// Errors are thrown as core::Error; the C binding turns them into a status
// and last_error.
#pragma once
#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "blvd/blvd.h"
#include "render/camera.h"
#include "render/context.h"
#include "render/renderer.h"
#include "runtime/cell_choice.h"
#include "runtime/cell_loader.h"
#include "runtime/cell_slots.h"
#include "runtime/link_prefetch.h"
#include "runtime/draw_list.h"
#include "runtime/frame_clock.h"
#include "runtime/memory_plan.h"
#include "stream/city.h"
#include "stream/frame_budget.h"
#include "stream/residency.h"
#include "track/tracker.h"

namespace blvd::runtime {

class Runtime {
 public:
  // `desc` has its defaults applied and its fields checked (sdk/capi).
  // Throws core::Error naming what failed (Budget when the memory plan
  // exceeds a budget, NoMem when the host allocator fails).
  explicit Runtime(const blvd_runtime_desc& desc);
  ~Runtime();

  // Who places the camera: the host (setPose*) or the tracker.
  void setCameraSource(blvd_camera_source source);
  // The host places the camera (finite values, pitch within (-90, 90));
  // Misuse while the tracker does.
  void setPoseLocal(double x, double y, double heading_deg, double pitch_deg);
  void setPoseGeo(double lat, double lon, double heading_deg, double pitch_deg);
  // Both: Status::OffMap for a pose off the map, which then draws sky and ground until the next pose.
  void setMode(blvd_render_mode mode, float radius_m);
  void setLinkMode(blvd_link_mode mode);
  void setRoute(const uint32_t* cells, size_t n);
  void waitResident(double timeout_ms);

  // One frame of the current pose: the whole frame, or `n` views of it.
  void render(blvd_frame_stats* stats, const blvd_view* views = nullptr, uint32_t n = 0);
  void readPixels(void* rgba, size_t bytes);
  // The last frame's draw list again as an object-id buffer (blvd_read_items).
  void readItems(uint32_t* ids, size_t count);
  void info(blvd_runtime_info* out) const;
  void stats(blvd_stats* out) const;

  // Tracking. The feeds are safe from any thread and never touch last_error
  // (another thread may be reading it); pose() runs on the render thread.
  // None of them moves the camera: setCameraSource does.
  void feedGnss(const track::GnssFix& fix);
  void feedOdometry(const track::Odometry& odo);
  // On terrain (ELEV) a matched pose's camera stands on the road: its eye
  // eye_height_m above it, its pitch the road's grade (as blvd_render's).
  const track::Pose& pose(double t);
  // False when the start pose is impossible (track::Tracker::setStartPose).
  bool setStartPose(const track::StartPose& sp);
  track::Tracker& tracker() { return *tracker_; }
  const geo::LocalFrame& frame() const { return city_.frame(); }
  // The renderer, for the tests' fault injection (Renderer::api()).
  render::Renderer& renderer() { return *renderer_; }
  // The last frame's camera (its eye east, north, up in the package frame).
  const render::Camera& camera() const { return cam_; }

  std::string last_error;

 private:
  void logPageCaches() const;
  // The camera from the tracker when it drives, then the current cell.
  uint32_t currentCell(double& arc_m, double& speed_mps);
  uint32_t streamCell(double& arc_m);  // streamSteps, degraded when the map has not arrived (frame.cpp)
  // Throws the renderer's error: Backend when the GL context was lost (the
  // runtime must be created again), Internal otherwise (frame.cpp).
  [[noreturn]] void renderFailed() const;
  // On a package with terrain: the eye eye_height_m above the road at
  // (cell, arc) and the pose's pitch plus the road's grade there (frame.cpp).
  void onRoad(uint32_t cell, double arc_m, double pose_pitch_deg, double& eye_u, double& pitch_deg) const;
  uint32_t streamSteps(double& arc_m, double upload_budget_ms);  // currentCell, its slots streamed, the link planned
  // Whether `e` says the map (table pages of a package on a server) has not arrived.
  bool mapMissing(const core::Error& e) const;
  void noteFeed(double t);
  bool referenceMode() const { return mode_ == BLVD_MODE_FULL || mode_ == BLVD_MODE_RADIUS; }
  // frame.cpp
  uint32_t frameCameras(const blvd_view* views, uint32_t n);
  void renderViews(uint32_t n, const render::RenderOptions& ro, render::FrameStats& fs,
                   uint64_t& full_pixels);
  render::Camera viewCamera(const blvd_view& v, uint32_t i) const;
  void afterFrame(double frame_ms, const render::FrameStats& fs, uint64_t full_pixels, double scale);
  void writeFrameStats(blvd_frame_stats* out, const render::FrameStats& fs, uint32_t cell) const;
  void placeCamera(double x, double y, double heading_deg, double pitch_deg, const double* lat_lon);

  blvd_runtime_desc desc_;
  stream::City city_;
  bool map_missing_ = false;  // this frame's map (table pages) had not arrived: degraded
  bool host_off_map_ = false; // the last host pose was refused as off the map (graph::onMap)
  bool off_map_ = false;      // this frame's camera is off the map: sky and ground only
  uint64_t map_waits_ = 0;    // frames that were (counted in blvd_stats.link_waits)
  double speed_mps_ = 0;      // the last frame's vehicle speed (blvd_stats.cached_ahead_s)
  MemoryPlan plan_;
  std::unique_ptr<CellLoader> loader_;
  std::unique_ptr<render::Context> ctx_;
  std::unique_ptr<render::Renderer> renderer_;
  std::unique_ptr<stream::Residency> residency_;
  std::unique_ptr<CellSlots> slots_;
  std::unique_ptr<DrawList> draw_;
  std::unique_ptr<TerrainSet> terrain_;
  std::vector<render::MeshHandle> terrain_tiles_;  // a frame's, sized at create
  std::unique_ptr<CellChoice> choice_;
  std::unique_ptr<stream::FrameBudget> budget_;  // with target_frame_ms
  FrameClock* clock_ = nullptr;  // this runtime's frames, for the loaders' gap scheduling
  render::Camera cam_;
  render::Camera frame_cams_[DrawList::kMaxViews];  // this frame's: cam_, or each view's
  double pose_pitch_deg_ = 0;  // the pose's pitch; cam_'s adds the road's grade on terrain (frame.cpp)
  track::Pose posed_;          // pose()'s answer, on the road's ground where the package has terrain
  blvd_render_mode mode_ = BLVD_MODE_BLVD;
  float radius_m_ = 250.f;
  bool rendered_ = false;
  bool items_drawn_ = false;  // readItems drew over the frame
  blvd_stats stats_{};        // the frame's own figures; the pools' are read in stats()
  uint64_t gpu_capacity_ = 0;  // the slabs' bytes as the GL reported them at create
  std::unique_ptr<track::Tracker> tracker_;
  blvd_camera_source camera_source_ = BLVD_CAMERA_HOST;  // render thread
  std::atomic<double> last_feed_t_{0.0};  // the newest fed time, from any feeding thread
  std::unique_ptr<LinkPrefetch> link_prefetch_;  // last: its thread reads city_ and stops first
};

}  // namespace blvd::runtime
