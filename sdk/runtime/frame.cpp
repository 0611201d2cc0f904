// One frame: which cell, streaming within the upload budget, the draw list,
// the render (whole frame or views), the frame budget's next step, and the
// read-backs of the frame (pixels, object ids).
#include <sched.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "core/math.h"
#include "core/sized.h"
#include "runtime/runtime.h"

namespace blvd::runtime {
using core::Error;
using core::Status;

void Runtime::render(blvd_frame_stats* stats, const blvd_view* views, uint32_t n) {
  if (!ctx_->makeCurrent()) throw Error(Status::Misuse, "the GL context cannot be made current on this thread");
  const auto t_frame = std::chrono::steady_clock::now();
  if (clock_) clock_->begin(monoNs(t_frame));
  loader_->keepOffCpu(::sched_getcpu());
  double arc_m = 0;
  const uint32_t cell = streamCell(arc_m);
  // On terrain the eye is eye_height_m above the road where the camera is
  // (the package's ELEV, linear along the cell), and the pose's pitch is
  // taken from the road's grade there, as a car's camera sits; flat packages
  // keep the pose as given.
  if (cell != graph::kNone) onRoad(cell, arc_m, pose_pitch_deg_, cam_.eye_enu.z, cam_.pitch_deg);
  const uint32_t n_cams = frameCameras(views, n);
  if (off_map_)
    draw_->clear();  // sky and ground, in every mode
  else
    draw_->build(mode_, radius_m_, cell, arc_m, frame_cams_, n_cams, *slots_, budget_.get());
  if (!off_map_) {
    draw_->addTerrain(terrain_tiles_.data(), terrain_->frame(cam_, terrain_tiles_.data()));
    link_prefetch_->wantTerrain(terrain_->uncachedBlobs());  // a package on a server: tiles not cached yet
  }
  render::FrameStats fs;
  render::RenderOptions ro;
  ro.scale = budget_ ? budget_->scale() : 1.0;
  ro.behind_from = draw_->behindFrom();
  uint64_t full_pixels = 0;
  if (!views) {
    full_pixels = uint64_t(cam_.width) * uint64_t(cam_.height);
    if (!renderer_->render(cam_, draw_->meshes(), draw_->size(), &fs, ro))
      renderFailed();
  } else {
    renderViews(n_cams, ro, fs, full_pixels);
  }
  rendered_ = true;
  items_drawn_ = false;
  const auto t_drawn = std::chrono::steady_clock::now();
  if (clock_) clock_->end(monoNs(t_drawn));
  // The whole call counts against the target: streaming and uploads too.
  afterFrame(std::chrono::duration<double, std::milli>(t_drawn - t_frame).count(), fs, full_pixels, ro.scale);
  if (stats) writeFrameStats(stats, fs, cell);
}

void Runtime::onRoad(uint32_t cell, double arc_m, double pose_pitch_deg, double& eye_u, double& pitch_deg) const {
  double u = eye_u, pitch = pose_pitch_deg;
  if (city_.cameraOnRoad(cell, arc_m, desc_.eye_height_m, u, pitch)) eye_u = u, pitch_deg = pitch;
}

void Runtime::renderFailed() const {
  throw Error(renderer_->contextLost() ? Status::Backend : Status::Internal, "render failed: " + renderer_->lastError());
}

// The cell the vehicle is in, its slots streamed. A package on a server may
// not have the map of where the vehicle is yet (its table pages: offline, or
// the link down): the frame then draws the last cell it drew, degraded.
uint32_t Runtime::streamCell(double& arc_m) {
  map_missing_ = false;
  const stream::City::NoLinkWait no_wait;
  try {
    return streamSteps(arc_m, desc_.upload_budget_ms);
  } catch (const Error& e) {
    if (!mapMissing(e)) throw;
    map_missing_ = true;
    ++map_waits_;
    last_error = e.what();
    arc_m = 0;
    return draw_->lastDrawnCell();
  }
}

uint32_t Runtime::streamSteps(double& arc_m, double upload_budget_ms) {
  double speed;
  const uint32_t cell = currentCell(arc_m, speed);
  speed_mps_ = speed;
  if (referenceMode()) {
    draw_->ensureReferenceBlocks(*renderer_);
    return cell;
  }
  const uint64_t errors = slots_->counters().load_errors;
  slots_->stream(*residency_, cell, arc_m, speed, upload_budget_ms);
  if (slots_->counters().load_errors != errors) last_error = slots_->lastError();  // blvd_stats.load_errors
  link_prefetch_->plan(cell, *residency_, speed);
  return cell;
}

// The frame's cameras into frame_cams_: the whole frame's, or each view's
// (checked before anything is drawn); their count.
uint32_t Runtime::frameCameras(const blvd_view* views, uint32_t n) {
  if (!views) {
    frame_cams_[0] = cam_;
    return 1;
  }
  if (n == 0 || n > DrawList::kMaxViews) throw Error(Status::InvalidArg, "need 1..16 views");
  for (uint32_t i = 0; i < n; ++i) frame_cams_[i] = viewCamera(core::sized(views[i]), i);
  return n;
}

// One draw list for every view (Yilmaz et al. §3.4); each view only changes
// the camera.
void Runtime::renderViews(uint32_t n, const render::RenderOptions& ro, render::FrameStats& fs,
                          uint64_t& full_pixels) {
  for (uint32_t i = 0; i < n; ++i) {
    const render::Camera& c = frame_cams_[i];
    render::FrameStats one;
    if (!renderer_->render(c, draw_->meshes(), draw_->size(), &one, ro))
      renderFailed();
    full_pixels += uint64_t(c.width) * uint64_t(c.height);
    fs.pixels += one.pixels;
    fs.frame_ms += one.frame_ms;
    fs.triangles += one.triangles;
    fs.draw_calls += one.draw_calls;
  }
  renderer_->setReadSize(int(desc_.width), int(desc_.height));
}

// View i's camera: the frame's camera turned, tilted, moved right of the
// heading and clipped to the view's rectangle of the frame.
render::Camera Runtime::viewCamera(const blvd_view& v, uint32_t i) const {
  const uint32_t W = desc_.width, H = desc_.height;
  const uint32_t w = v.width ? v.width : W, h = v.height ? v.height : H;
  if (v.x >= W || v.y >= H || w > W - v.x || h > H - v.y)
    throw Error(Status::InvalidArg, "view " + std::to_string(i) + " lies outside the " + std::to_string(W) + "x" +
                                        std::to_string(H) + " frame");
  if (!std::isfinite(v.yaw_offset_deg) || !std::isfinite(v.pitch_offset_deg) || !std::isfinite(v.eye_offset_right_m) ||
      !(v.fov_y_deg == 0 || (v.fov_y_deg > 1 && v.fov_y_deg < 179)))
    throw Error(Status::InvalidArg, "view " + std::to_string(i) + " has an angle or offset out of range");
  render::Camera c = cam_;
  c.width = int(w);
  c.height = int(h);
  c.viewport_x = int(v.x);
  c.viewport_y = int(H - v.y - h);  // GL counts rows from the bottom
  c.heading_deg = std::fmod(cam_.heading_deg + v.yaw_offset_deg + 720.0, 360.0);
  c.pitch_deg = std::clamp(cam_.pitch_deg + v.pitch_offset_deg, -89.0, 89.0);
  if (v.fov_y_deg > 0) c.fov_y_deg = v.fov_y_deg;
  const double hr = cam_.heading_deg * core::kDegToRad;
  c.eye_enu.x += std::cos(hr) * v.eye_offset_right_m;  // right of the heading
  c.eye_enu.y -= std::sin(hr) * v.eye_offset_right_m;
  c.mirror = (v.flags & BLVD_VIEW_MIRROR) != 0;
  return c;
}

void Runtime::afterFrame(double frame_ms, const render::FrameStats& fs, uint64_t full_pixels, double scale) {
  if (budget_ && !referenceMode()) {
    budget_->next(frame_ms, draw_->blockTriangles(), draw_->floorTriangles(), fs.pixels, full_pixels);
    stats_.polygon_budget = budget_->polygonBudget();
    stats_.frame_aim_ms = float(budget_->aim());
    stats_.budget_unreachable = budget_->unreachable() ? 1 : 0;
  }
  stats_.render_scale = float(scale);
  stats_.block_triangles = draw_->blockTriangles();
  ++stats_.frames;
  stats_.frame_ms = fs.frame_ms;
  stats_.triangles = fs.triangles;
}

void Runtime::writeFrameStats(blvd_frame_stats* out, const render::FrameStats& fs, uint32_t cell) const {
  const uint32_t size = out->struct_size ? out->struct_size : sizeof(blvd_frame_stats);
  blvd_frame_stats s{};
  s.struct_size = size;
  s.frame_ms = fs.frame_ms;
  s.triangles = fs.triangles;
  s.draw_calls = fs.draw_calls;
  s.cell = cell;
  s.impostor_layers = draw_->impostors();
  s.blocks_drawn = draw_->blocks();
  s.flags = (draw_->degraded() || map_missing_ ? BLVD_FRAME_DEGRADED : 0) | (off_map_ ? BLVD_FRAME_OFF_MAP : 0);
  std::memcpy(out, &s, std::min<size_t>(size, sizeof s));
}

void Runtime::readPixels(void* rgba, size_t bytes) {
  if (!rendered_) throw Error(Status::Misuse, "blvd_read_pixels before blvd_render");
  if (items_drawn_)
    throw Error(Status::Misuse, "blvd_read_pixels after blvd_read_items: the ids replaced the frame; render again");
  const size_t need = static_cast<size_t>(renderer_->lastWidth()) * renderer_->lastHeight() * 4;
  if (bytes < need)
    throw Error(Status::InvalidArg, "pixel buffer holds " + std::to_string(bytes) + " bytes, the frame needs " +
                                        std::to_string(need));
  if (!renderer_->readPixels(static_cast<uint8_t*>(rgba))) throw Error(Status::Internal, renderer_->lastError());
}

void Runtime::readItems(uint32_t* ids, size_t count) {
  if (!rendered_) throw Error(Status::Misuse, "blvd_read_items before blvd_render");
  const size_t need = size_t(cam_.width) * size_t(cam_.height);
  if (count < need)
    throw Error(Status::InvalidArg, "id buffer holds " + std::to_string(count) + " ids, the frame needs " +
                                        std::to_string(need));
  if (!ctx_->makeCurrent()) throw Error(Status::Misuse, "the GL context cannot be made current on this thread");
  render::RenderOptions ro;
  ro.pass = render::Pass::ItemBuffer;
  ro.item_ids = draw_->items();
  ro.behind_from = draw_->behindFrom();
  if (!renderer_->render(cam_, draw_->meshes(), draw_->size(), nullptr, ro))
    throw Error(Status::Internal, "item buffer failed: " + renderer_->lastError());
  items_drawn_ = true;
  // The RGBA read-back is unpacked in place: 4 bytes a pixel, one id a pixel.
  auto* px = reinterpret_cast<uint8_t*>(ids);
  if (!renderer_->readPixels(px)) throw Error(Status::Internal, renderer_->lastError());
  for (size_t i = 0; i < need; ++i) {
    const uint8_t* p = px + 4 * i;
    ids[i] = p[3] ? uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 : 0u;
  }
}

}  // namespace blvd::runtime
