#include "capi/runtime.h"
#include "capi/track_convert.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/log.h"

namespace blvd::capi {
namespace {
constexpr size_t kImpostorCacheCells = 16;
}
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
  // Every block, plus the impostor cache: kImpostorCacheCells cells of at
  // most the package's largest per-cell impostor count.
  size_t per_cell = 0;
  for (const auto& c : city_.cellTables().impostors) per_cell = std::max(per_cell, c.layered.size() + c.single.size());
  rd.mesh_capacity = static_cast<uint32_t>(city_.blocks().size() + kImpostorCacheCells * per_cell + 1);
  renderer_ = render::Renderer::create(*ctx_, rd, err);
  if (!renderer_) throw Error(Status::Backend, err);

  // Every block resident. Fixed-budget streaming replaces this.
  geo::MeshData mesh;
  block_meshes_.resize(city_.blocks().size());
  for (uint32_t b = 0; b < city_.blocks().size(); ++b) {
    st = city_.decodeBlock(b, mesh, err);
    if (st != Status::Ok) throw Error(st, err);
    if (mesh.empty()) continue;
    block_meshes_[b] = renderer_->upload(mesh);
    if (block_meshes_[b].id == 0)
      throw Error(Status::Internal, "block " + std::to_string(b) + ": " + renderer_->lastError());
  }
  draw_.reserve(block_meshes_.size() + 64);
  cache_.resize(kImpostorCacheCells);
  setMode(desc.mode, desc.radius_m);
  cam_.fov_y_deg = desc.fov_y_deg;
  cam_.far_m = desc.far_m;
  cam_.width = static_cast<int>(desc.width);
  cam_.height = static_cast<int>(desc.height);
  cam_.eye_enu = {0, 0, desc.eye_height_m};
  track::TrackerDesc td;
  td.eye_height_m = desc.eye_height_m;
  tracker_ = std::make_unique<track::Tracker>(city_.frame(), &city_.graph(), td);
  BLVD_LOG_INFO("runtime: %s, %zu blocks on %s (%s)", desc.package_path, block_meshes_.size(), ctx_->name(),
                renderer_->glRenderer());
}

Runtime::~Runtime() {
  if (renderer_ && ctx_ && ctx_->makeCurrent()) {
    for (render::MeshHandle h : block_meshes_) renderer_->release(h);
    for (auto& c : cache_) {
      for (render::MeshHandle h : c.layered) renderer_->release(h);
      for (render::MeshHandle h : c.single) renderer_->release(h);
    }
  }
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
  manual_pose_ = true;
}

// The C flags are the tracker's bits, so they pass through unchanged.
static_assert(BLVD_GNSS_HAS_LATLON == track::kGnssHasLatLon && BLVD_GNSS_HAS_HACC == track::kGnssHasHAcc &&
                  BLVD_GNSS_HAS_TRACK == track::kGnssHasTrack && BLVD_GNSS_HAS_HDOP == track::kGnssHasHdop,
              "GNSS flag bits");
static_assert(BLVD_ODO_SPEED == track::kOdoSpeed && BLVD_ODO_YAW_RATE == track::kOdoYawRate &&
                  BLVD_ODO_WHEEL_SPEEDS == track::kOdoWheelSpeeds && BLVD_ODO_GEAR == track::kOdoGear &&
                  BLVD_ODO_HEADING == track::kOdoHeading,
              "odometry flag bits");
static_assert(BLVD_POSE_VALID == track::kPoseValid && BLVD_POSE_MATCHED == track::kPoseMatched &&
                  BLVD_POSE_DEAD_RECKONING == track::kPoseDeadReckoning &&
                  BLVD_POSE_HEADING_VALID == track::kPoseHeadingValid,
              "pose flag bits");

blvd_status Runtime::feedGnss(const blvd_gnss_fix& in) {
  const track::GnssFix f = toTrack(in);
  tracker_->feedGnss(f);
  last_feed_t_ = std::max(last_feed_t_.load(), f.t);
  manual_pose_ = false;
  return BLVD_OK;
}

blvd_status Runtime::feedOdometry(const blvd_odometry& in) {
  const track::Odometry o = toTrack(in);
  tracker_->feedOdometry(o);
  last_feed_t_ = std::max(last_feed_t_.load(), o.t);
  manual_pose_ = false;
  return BLVD_OK;
}

void Runtime::getPose(double t, blvd_pose* out) {
  if (!std::isfinite(t)) throw Error(Status::InvalidArg, "blvd_get_pose: t is not finite");
  const track::Pose& p = tracker_->update(t);
  blvd_pose r{};
  r.struct_size = out->struct_size ? out->struct_size : sizeof r;
  r.t = p.t;
  r.x = p.e;
  r.y = p.n;
  double h = 0;
  city_.frame().reverse({p.e, p.n, 0}, r.lat, r.lon, h);
  r.heading_deg = p.heading_deg;
  r.speed_mps = p.speed_mps;
  r.cell = p.cell;
  r.arc_m = p.arc_m;
  r.lateral_m = p.lateral_m;
  r.confidence = p.confidence;
  r.flags = p.flags;  // BLVD_POSE_* == track::PoseFlag bits
  std::memcpy(out, &r, std::min<size_t>(r.struct_size, sizeof r));
}

void Runtime::setPoseGeo(double lat, double lon, double heading_deg, double pitch_deg) {
  if (!(lat >= -90 && lat <= 90) || !(lon >= -180 && lon <= 180))
    throw Error(Status::InvalidArg, "latitude/longitude out of range");
  const geo::Enu p = city_.frame().forward(lat, lon, 0);
  setPoseLocal(p.e, p.n, heading_deg, pitch_deg);
}

void Runtime::setMode(blvd_render_mode mode, float radius_m) {
  if (mode < BLVD_MODE_BLVD || mode > BLVD_MODE_SINGLE) throw Error(Status::InvalidArg, "unknown render mode");
  if (!(radius_m >= 0 && radius_m < 1e6)) throw Error(Status::InvalidArg, "radius_m out of range");
  if ((mode == BLVD_MODE_BLVD || mode == BLVD_MODE_SINGLE) && !city_.hasImpostors()) {
    if (mode == BLVD_MODE_SINGLE)
      throw Error(Status::Unsupported, "the package has no impostors (baked with --impostor none)");
    mode = BLVD_MODE_FULL;  // the default on a package without impostors
  }
  mode_ = mode;
  radius_m_ = radius_m > 0 ? radius_m : 250.f;
}

Runtime::CellImpostorCache& Runtime::impostorsOf(uint32_t cell) {
  for (auto& c : cache_)
    if (c.cell == cell) {
      c.last_used = frame_;
      return c;
    }
  // Replace the least recently used entry.
  CellImpostorCache* victim = &cache_[0];
  for (auto& c : cache_)
    if (c.last_used < victim->last_used) victim = &c;
  for (render::MeshHandle h : victim->layered) renderer_->release(h);
  for (render::MeshHandle h : victim->single) renderer_->release(h);
  victim->layered.clear();
  victim->single.clear();
  victim->cell = cell;
  victim->last_used = frame_;
  const graph::CellImpostors& ci = city_.cellTables().impostors[cell];
  geo::MeshData mesh;
  std::string err;
  for (int single = 0; single < 2; ++single)
    for (const graph::ImpostorLayer& layer : single ? ci.single : ci.layered) {
      const Status st = city_.decodeImpostor(layer, mesh, err);
      if (st != Status::Ok) throw Error(st, err);
      const render::MeshHandle h = renderer_->upload(mesh);
      if (h.id == 0) throw Error(Status::Internal, "impostor of cell " + std::to_string(cell) + ": " + renderer_->lastError());
      (single ? victim->single : victim->layered).push_back(h);
    }
  return *victim;
}

void Runtime::buildDrawList(uint32_t cell) {
  draw_.clear();
  impostors_drawn_ = 0;
  const auto& blocks = city_.blocks();
  auto addBlock = [&](uint32_t b) {
    if (b < block_meshes_.size() && block_meshes_[b].id) draw_.push_back(block_meshes_[b]);
  };
  const graph::StreetGraph& g = city_.graph();
  switch (mode_) {
    case BLVD_MODE_FULL:
      for (uint32_t b = 0; b < block_meshes_.size(); ++b) addBlock(b);
      break;
    case BLVD_MODE_RADIUS: {
      // Visibility radius (the VOP baseline): blocks whose box comes within R.
      const double ex = cam_.eye_enu.x, ez = -cam_.eye_enu.y;
      for (uint32_t b = 0; b < blocks.size(); ++b) {
        const auto& r = blocks[b];
        const double dx = std::max({double(r.bbox_min[0]) - ex, 0.0, ex - double(r.bbox_max[0])});
        const double dz = std::max({double(r.bbox_min[2]) - ez, 0.0, ez - double(r.bbox_max[2])});
        if (dx * dx + dz * dz <= double(radius_m_) * radius_m_) addBlock(b);
      }
      break;
    }
    case BLVD_MODE_LOCAL:
    case BLVD_MODE_BLVD:
    case BLVD_MODE_SINGLE:
    default:
      if (cell == graph::kNone) break;
      // Sillion 97 §3.1: the local model as geometry ...
      for (const uint32_t* b = g.local_blocks.begin(cell); b != g.local_blocks.end(cell); ++b) addBlock(*b);
      if (mode_ == BLVD_MODE_LOCAL) break;
      // ... plus the cell's impostors for the rest; the blocks they stand
      // for are never drawn with them (K06 §3.1.2): they are not local.
      {
        const CellImpostorCache& c = impostorsOf(cell);
        for (render::MeshHandle h : mode_ == BLVD_MODE_SINGLE ? c.single : c.layered) {
          draw_.push_back(h);
          ++impostors_drawn_;
        }
      }
      break;
  }
  blocks_drawn_ = static_cast<uint32_t>(draw_.size() - impostors_drawn_);
}

void Runtime::render(blvd_frame_stats* stats) {
  if (!ctx_->makeCurrent()) throw Error(Status::Misuse, "the GL context cannot be made current on this thread");
  ++frame_;
  uint32_t cell = graph::kNone;
  if (!manual_pose_) {
    // Tracking drives the camera: the pose at the newest fed time.
    const track::Pose& p = tracker_->update(last_feed_t_.load());
    if (p.flags & track::kPoseValid) {
      cam_.eye_enu = {p.camera.eye_e, p.camera.eye_n, p.camera.eye_u};
      cam_.heading_deg = p.camera.heading_deg;
      cam_.pitch_deg = p.camera.pitch_deg;
      if (p.flags & track::kPoseMatched) cell = p.cell;
    }
  }
  if (cell == graph::kNone) cell = city_.nearestCell({cam_.eye_enu.x, cam_.eye_enu.y}, cam_.heading_deg);
  buildDrawList(cell);
  render::FrameStats fs;
  if (!renderer_->render(cam_, draw_.data(), draw_.size(), &fs))
    throw Error(Status::Internal, "render failed: " + renderer_->lastError());
  rendered_ = true;
  if (stats) {
    const uint32_t size = stats->struct_size ? stats->struct_size : sizeof(blvd_frame_stats);
    blvd_frame_stats s{};
    s.struct_size = size;
    s.frame_ms = fs.frame_ms;
    s.triangles = fs.triangles;
    s.draw_calls = fs.draw_calls;
    s.cell = cell;
    s.impostor_layers = impostors_drawn_;
    s.blocks_drawn = blocks_drawn_;
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
