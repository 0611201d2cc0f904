// The object behind blvd_runtime*: the city, the GL context and renderer, the
// pose, and the last error. sdk/capi/blvd_capi.cpp maps the C API onto it.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "blvd/blvd.h"
#include "render/camera.h"
#include "render/context.h"
#include "render/renderer.h"
#include "stream/city.h"

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

  std::string last_error;

 private:
  blvd_runtime_desc desc_;
  stream::City city_;
  std::unique_ptr<render::Context> ctx_;
  std::unique_ptr<render::Renderer> renderer_;
  std::vector<render::MeshHandle> meshes_;  // every non-empty block (full model)
  render::Camera cam_;
  bool rendered_ = false;
};

}  // namespace blvd::capi
