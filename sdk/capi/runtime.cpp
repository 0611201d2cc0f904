#include "capi/runtime.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/log.h"

namespace blvd::capi {
using core::Error;
using core::Status;

Runtime::Runtime(const blvd_runtime_desc& desc) : desc_(desc) {
  std::string err;
  Status st = city_.open(desc.package_path, err);
  if (st != Status::Ok) throw Error(st, err);

  ctx_ = render::createContext(static_cast<render::Backend>(desc.backend), err);
  if (!ctx_) throw Error(Status::Backend, err);
  render::RendererDesc rd;
  rd.width = static_cast<int>(desc.width);
  rd.height = static_cast<int>(desc.height);
  rd.mesh_capacity = static_cast<uint32_t>(city_.blocks().size() + 16);
  renderer_ = render::Renderer::create(*ctx_, rd, err);
  if (!renderer_) throw Error(Status::Backend, err);

  // Full model: every block resident. Fixed-budget streaming replaces this.
  geo::MeshData mesh;
  for (uint32_t b = 0; b < city_.blocks().size(); ++b) {
    st = city_.decodeBlock(b, mesh, err);
    if (st != Status::Ok) throw Error(st, err);
    if (mesh.empty()) continue;
    const render::MeshHandle h = renderer_->upload(mesh);
    if (h.id == 0) throw Error(Status::Internal, "block " + std::to_string(b) + ": " + renderer_->lastError());
    meshes_.push_back(h);
  }
  cam_.fov_y_deg = desc.fov_y_deg;
  cam_.far_m = desc.far_m;
  cam_.width = static_cast<int>(desc.width);
  cam_.height = static_cast<int>(desc.height);
  cam_.eye_enu = {0, 0, desc.eye_height_m};
  BLVD_LOG_INFO("runtime: %s, %zu blocks on %s (%s)", desc.package_path, meshes_.size(), ctx_->name(),
                renderer_->glRenderer());
}

Runtime::~Runtime() {
  if (renderer_ && ctx_ && ctx_->makeCurrent())
    for (render::MeshHandle h : meshes_) renderer_->release(h);
  renderer_.reset();
  ctx_.reset();
}

void Runtime::setPoseLocal(double x, double y, double heading_deg, double pitch_deg) {
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(heading_deg) || !std::isfinite(pitch_deg))
    throw Error(Status::InvalidArg, "pose has a non-finite value");
  if (pitch_deg <= -90 || pitch_deg >= 90) throw Error(Status::InvalidArg, "pitch must be within (-90, 90) degrees");
  cam_.eye_enu = {x, y, desc_.eye_height_m};
  cam_.heading_deg = std::fmod(heading_deg, 360.0);
  cam_.pitch_deg = pitch_deg;
}

void Runtime::setPoseGeo(double lat, double lon, double heading_deg, double pitch_deg) {
  if (!(lat >= -90 && lat <= 90) || !(lon >= -180 && lon <= 180))
    throw Error(Status::InvalidArg, "latitude/longitude out of range");
  const geo::Enu p = city_.frame().forward(lat, lon, 0);
  setPoseLocal(p.e, p.n, heading_deg, pitch_deg);
}

void Runtime::render(blvd_frame_stats* stats) {
  if (!ctx_->makeCurrent()) throw Error(Status::Misuse, "the GL context cannot be made current on this thread");
  render::FrameStats fs;
  if (!renderer_->render(cam_, meshes_.data(), meshes_.size(), &fs))
    throw Error(Status::Internal, "render failed: " + renderer_->lastError());
  rendered_ = true;
  if (stats) {
    const uint32_t size = stats->struct_size ? stats->struct_size : sizeof(blvd_frame_stats);
    blvd_frame_stats s{};
    s.struct_size = size;
    s.frame_ms = fs.frame_ms;
    s.triangles = fs.triangles;
    s.draw_calls = fs.draw_calls;
    std::memcpy(stats, &s, std::min<size_t>(size, sizeof s));
  }
}

void Runtime::readPixels(void* rgba, size_t bytes) {
  if (!rendered_) throw Error(Status::Misuse, "blvd_read_pixels before blvd_render");
  const size_t need = static_cast<size_t>(renderer_->lastWidth()) * renderer_->lastHeight() * 4;
  if (bytes < need)
    throw Error(Status::InvalidArg, "pixel buffer holds " + std::to_string(bytes) + " bytes, the frame needs " +
                                        std::to_string(need));
  if (!renderer_->readPixels(static_cast<uint8_t*>(rgba))) throw Error(Status::Internal, renderer_->lastError());
}

void Runtime::info(blvd_runtime_info* out) const {
  blvd_runtime_info i{};
  i.struct_size = out->struct_size ? out->struct_size : sizeof i;
  i.backend = ctx_->name();
  i.gl_renderer = renderer_->glRenderer();
  i.gl_version = renderer_->glVersion();
  i.origin_lat = city_.header().origin_lat;
  i.origin_lon = city_.header().origin_lon;
  i.cell_count = city_.header().cell_count;
  i.block_count = city_.header().block_count;
  i.building_count = city_.header().building_count;
  i.triangle_count = city_.header().triangle_count;
  std::memcpy(out, &i, std::min<size_t>(i.struct_size, sizeof i));
}

}  // namespace blvd::capi
