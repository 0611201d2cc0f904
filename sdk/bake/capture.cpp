#include "bake/capture.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

#include "bake/street_points.h"
#include "core/status.h"

namespace blvd::bake {
namespace {
constexpr double kMaxDepth = 8192.0;
// A face is near-horizontal when its normal is within ~45° of up or down.
constexpr double kHorizontalCos = 0.7;

bool nearHorizontal(const std::vector<float>& p, const uint32_t* t) {
  auto at = [&](uint32_t i) { return glm::dvec3(p[i * 3], p[i * 3 + 1], p[i * 3 + 2]); };
  const glm::dvec3 n = glm::cross(at(t[1]) - at(t[0]), at(t[2]) - at(t[0]));
  const double len = glm::length(n);
  return len > 0 && std::abs(n.y) >= kHorizontalCos * len;  // glTF: y is up
}
}  // namespace

geo::MeshData outlineLines(const geo::MeshData& mesh) {
  std::vector<uint64_t> edges;  // undirected (lo << 32 | hi), once per horizontal triangle
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    const uint32_t* v = &mesh.indices[t];
    if (!nearHorizontal(mesh.positions, v)) continue;
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = v[k], b = v[(k + 1) % 3];
      edges.push_back(uint64_t(std::min(a, b)) << 32 | std::max(a, b));
    }
  }
  std::sort(edges.begin(), edges.end());
  geo::MeshData out;
  std::vector<uint32_t> remap(mesh.vertexCount(), UINT32_MAX);
  auto vertex = [&](uint32_t i) {
    if (remap[i] == UINT32_MAX) {
      remap[i] = static_cast<uint32_t>(out.vertexCount());
      out.positions.insert(out.positions.end(), &mesh.positions[i * 3], &mesh.positions[i * 3] + 3);
    }
    return remap[i];
  };
  for (size_t i = 0; i < edges.size();) {
    size_t j = i + 1;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if (j - i == 1) out.indices.insert(out.indices.end(), {vertex(uint32_t(edges[i] >> 32)), vertex(uint32_t(edges[i]))});
    i = j;
  }
  return out;
}

PinholeCamera pinholeOf(const render::Camera& cam) {
  PinholeCamera p;
  const glm::dmat3 cam_to_world = glm::transpose(glm::dmat3(render::viewRotation(cam)));
  p.right = cam_to_world[0];
  p.up = cam_to_world[1];
  p.forward = -cam_to_world[2];
  p.eye = render::enuToGltf(cam.eye_enu);
  p.tan_half_y = std::tan(glm::radians(cam.fov_y_deg) * 0.5);
  p.tan_half_x = p.tan_half_y * double(cam.width) / double(cam.height);
  p.width = cam.width;
  p.height = cam.height;
  return p;
}

CaptureRig::CaptureRig(const std::vector<geo::MeshData>& block_meshes, int max_width, int max_height,
                       render::Backend backend, const std::vector<bool>& draw)
    : max_w_(max_width), max_h_(max_height) {
  std::string err;
  ctx_ = render::createContext(backend, err);
  if (!ctx_) throw core::Error(core::Status::Backend, "bake capture: " + err);
  render::RendererDesc rd;
  rd.width = max_width;
  rd.height = max_height;
  rd.mesh_capacity = static_cast<uint32_t>(2 * block_meshes.size() + 1);  // each block and its outline
  renderer_ = render::Renderer::create(*ctx_, rd, err);
  if (!renderer_) throw core::Error(core::Status::Backend, "bake capture: " + err);
  handles_.resize(block_meshes.size());
  outlines_.resize(block_meshes.size());
  for (size_t b = 0; b < block_meshes.size(); ++b) {
    if (block_meshes[b].empty() || !(draw.empty() || draw[b])) continue;
    handles_[b] = renderer_->upload(block_meshes[b]);
    const geo::MeshData lines = outlineLines(block_meshes[b]);
    if (!lines.empty()) outlines_[b] = renderer_->uploadLines(lines);
  }
  pixels_.resize(size_t(max_width) * max_height * 4);
  depth_pixels_.resize(pixels_.size());
}

CaptureRig::~CaptureRig() = default;

void CaptureRig::drawIds(const render::Camera& cam, const char* what, bool keep_depth) {
  render::RenderOptions opt;
  opt.pass = render::Pass::ItemBuffer;
  opt.item_ids = ids_.data();
  opt.keep_depth = keep_depth;
  if (!renderer_->render(cam, list_.data(), list_.size(), nullptr, opt) || !renderer_->readPixels(pixels_.data()))
    throw core::Error(core::Status::Internal, std::string(what) + ": " + renderer_->lastError());
}

void CaptureRig::addIdCounts(size_t n, std::vector<uint32_t>& counts) const {
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* p = &pixels_[i * 4];
    if (p[3] == 0) continue;
    const uint32_t id = uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16;
    if (id >= 1 && id <= counts.size()) ++counts[id - 1];
  }
}

// Lists `meshes` (per block) with their ids (block + 1); with `skip`, not
// the blocks it counts pixels of.
void CaptureRig::listBlocks(const std::vector<render::MeshHandle>& meshes, const std::vector<uint32_t>* skip) {
  list_.clear();
  ids_.clear();
  for (size_t b = 0; b < meshes.size(); ++b) {
    if (meshes[b].id == 0 || (skip && (*skip)[b])) continue;
    list_.push_back(meshes[b]);
    ids_.push_back(static_cast<uint32_t>(b + 1));
  }
}

void CaptureRig::itemBuffer(const render::Camera& cam, std::vector<uint32_t>& counts,
                            std::vector<uint32_t>* outline_counts) {
  const size_t n = size_t(cam.width) * cam.height;
  view_counts_.assign(handles_.size(), 0u);
  listBlocks(handles_);
  drawIds(cam, "bake item buffer");
  addIdCounts(n, view_counts_);
  for (size_t b = 0; b < counts.size() && b < view_counts_.size(); ++b) counts[b] += view_counts_[b];
  if (!outline_counts) return;
  listBlocks(outlines_, &view_counts_);  // only blocks no pixel centre fell on
  drawIds(cam, "bake item buffer (outlines)", true);
  addIdCounts(n, *outline_counts);
}

void CaptureRig::coverage(const render::Camera& cam, const std::vector<uint32_t>& blocks, std::vector<uint8_t>& mask,
                          std::vector<uint32_t>* counts) {
  list_.clear();
  ids_.clear();
  for (size_t i = 0; i < blocks.size(); ++i)
    if (blocks[i] < handles_.size() && handles_[blocks[i]].id != 0)
      list_.push_back(handles_[blocks[i]]), ids_.push_back(static_cast<uint32_t>(i + 1));
  drawIds(cam, "bake coverage");
  const size_t n = size_t(cam.width) * cam.height;
  mask.resize(n);
  for (size_t i = 0; i < n; ++i) mask[i] = pixels_[i * 4 + 3] != 0;
  if (counts) addIdCounts(n, *counts);
}

bool CaptureRig::insideGeometry(const glm::dvec3& eye_enu) {
  render::Camera cam;
  cam.eye_enu = eye_enu;
  cam.pitch_deg = 89.0;
  cam.fov_y_deg = 2.0;
  cam.width = cam.height = 4;
  cam.near_m = 0.05;
  cam.far_m = kViewDistanceM;
  list_.clear();
  for (const render::MeshHandle& h : handles_)
    if (h.id != 0) list_.push_back(h);
  render::RenderOptions opt;
  opt.pass = render::Pass::CaptureColor;  // back faces in alpha 128, culling off
  if (!renderer_->render(cam, list_.data(), list_.size(), nullptr, opt) || !renderer_->readPixels(pixels_.data()))
    throw core::Error(core::Status::Internal, "bake inside test: " + renderer_->lastError());
  return pixels_[(2 * 4 + 2) * 4 + 3] == 128;
}

void CaptureRig::capture(const render::Camera& cam, const std::vector<uint32_t>& blocks, CaptureImage& out,
                         PinholeCamera& pinhole) {
  list_.clear();
  for (uint32_t b : blocks)
    if (b < handles_.size() && handles_[b].id != 0) list_.push_back(handles_[b]);
  render::RenderOptions opt;
  opt.pass = render::Pass::CaptureColor;
  if (!renderer_->render(cam, list_.data(), list_.size(), nullptr, opt) || !renderer_->readPixels(pixels_.data()))
    throw core::Error(core::Status::Internal, "bake capture: " + renderer_->lastError());
  opt.pass = render::Pass::CaptureDepth;
  opt.max_depth_m = kMaxDepth;
  if (!renderer_->render(cam, list_.data(), list_.size(), nullptr, opt) ||
      !renderer_->readPixels(depth_pixels_.data()))
    throw core::Error(core::Status::Internal, "bake capture: " + renderer_->lastError());
  const size_t n = size_t(cam.width) * cam.height;
  out.width = cam.width;
  out.height = cam.height;
  out.rgba.assign(pixels_.begin(), pixels_.begin() + n * 4);
  out.depth.resize(n);
  out.mask.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const double z = render::unpackCaptureDepth(&depth_pixels_[i * 4], kMaxDepth);
    // Alpha 255 = geometry; 128 = an underside (the paper's special colour),
    // which occludes but is not part of the impostor; 0 = nothing.
    out.mask[i] = pixels_[i * 4 + 3] == 255 && z > 0 ? 1 : 0;
    out.depth[i] = z > 0 ? static_cast<float>(z) : std::numeric_limits<float>::infinity();
  }
  pinhole = pinholeOf(cam);
}

}  // namespace blvd::bake
