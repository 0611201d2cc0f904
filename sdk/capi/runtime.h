// The object behind blvd_runtime*: the city, the GL context and renderer, the
// pose, and the last error. sdk/capi/blvd_capi.cpp maps the C API onto it.
#pragma once
#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "blvd/blvd.h"
#include "render/camera.h"
#include "render/context.h"
#include "render/renderer.h"
#include "stream/city.h"
#include "track/tracker.h"

namespace blvd::capi {

class Runtime {
 public:
  // Throws core::Error naming what failed.
  explicit Runtime(const blvd_runtime_desc& desc);
  ~Runtime();

  void setPoseLocal(double x, double y, double heading_deg, double pitch_deg);
  void setPoseGeo(double lat, double lon, double heading_deg, double pitch_deg);
  void render(blvd_frame_stats* stats);
  void readPixels(void* rgba, size_t bytes);
  void info(blvd_runtime_info* out) const;
  void setMode(blvd_render_mode mode, float radius_m);

  // Tracking. The feeds are safe from any thread and never touch last_error
  // (another thread may be reading it); getPose runs on the render thread.
  blvd_status feedGnss(const blvd_gnss_fix& fix);
  blvd_status feedOdometry(const blvd_odometry& odo);
  void getPose(double t, blvd_pose* out);

  std::string last_error;

 private:
  blvd_runtime_desc desc_;
  stream::City city_;
  std::unique_ptr<render::Context> ctx_;
  std::unique_ptr<render::Renderer> renderer_;
  // Impostor meshes of recently visited cells (a small LRU; fixed-budget
  // streaming replaces it).
  struct CellImpostorCache {
    uint32_t cell = 0xffffffffu;
    std::vector<render::MeshHandle> layered, single;
    uint64_t last_used = 0;
  };
  void buildDrawList(uint32_t cell);
  CellImpostorCache& impostorsOf(uint32_t cell);

  std::vector<render::MeshHandle> block_meshes_;  // per block (id 0 when empty); all resident for now
  std::vector<render::MeshHandle> draw_;          // this frame's list
  std::vector<CellImpostorCache> cache_;
  uint64_t frame_ = 0;
  blvd_render_mode mode_ = BLVD_MODE_BLVD;
  float radius_m_ = 250.f;
  uint32_t impostors_drawn_ = 0, blocks_drawn_ = 0;
  render::Camera cam_;
  bool rendered_ = false;
  // The tracker drives the camera once it has a pose, until the host places
  // the camera itself (blvd_set_pose_*); the next feed hands it back.
  std::unique_ptr<track::Tracker> tracker_;
  std::atomic<bool> manual_pose_{true};
  std::atomic<double> last_feed_t_{0.0};
};

}  // namespace blvd::capi
