// Capture planning for a cell's impostors; the rule is in capture_plan.h.
#include "bake/capture_plan.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

namespace blvd::bake {
namespace {

constexpr double kMaxScoutSpanDeg = 90.0;
constexpr int kGapBins = 15;  // covered azimuths closer than this (1° bins) stay one interval

// Horizontal unit vectors (glTF axes) of a heading, clockwise from north.
glm::dvec3 forwardOf(double heading_deg) {
  const double h = glm::radians(heading_deg);
  return {std::sin(h), 0.0, -std::cos(h)};
}
glm::dvec3 rightOf(double heading_deg) {
  const double h = glm::radians(heading_deg);
  return {std::cos(h), 0.0, std::sin(h)};
}

int ceil4(double v) { return (static_cast<int>(std::ceil(v)) + 3) / 4 * 4; }

// The azimuth of unit direction `d` (glTF axes) from the reference heading.
double azimuthOf(const glm::dvec3& d, double heading_deg) {
  return glm::degrees(std::atan2(glm::dot(d, rightOf(heading_deg)), glm::dot(d, forwardOf(heading_deg))));
}

// The scout: covered pixels of `blocks` over the azimuth range, as rays;
// `seen` gets each block's pixel count (by its index in blocks).
std::vector<CoveredRay> scout(CaptureRig& rig, const glm::dvec3& eye_enu, double heading_deg, double az_lo,
                              double az_hi, const std::vector<uint32_t>& blocks, const CapturePlanOptions& opt,
                              std::vector<uint32_t>& seen) {
  std::vector<CoveredRay> rays;
  seen.assign(blocks.size(), 0);
  const int k = std::max(1, static_cast<int>(std::ceil((az_hi - az_lo) / kMaxScoutSpanDeg - 1e-9)));
  const double span = (az_hi - az_lo) / k;
  std::vector<uint8_t> mask;
  for (int j = 0; j < k; ++j) {
    render::Camera cam;
    cam.eye_enu = eye_enu;
    cam.heading_deg = heading_deg + az_lo + (j + 0.5) * span;
    cam.pitch_deg = 0.5 * (opt.min_elevation_deg + opt.max_elevation_deg);
    cam.fov_y_deg = opt.max_elevation_deg - opt.min_elevation_deg;
    const double tx = std::tan(glm::radians(0.5 * span + 1.0)), ty = std::tan(glm::radians(0.5 * cam.fov_y_deg));
    cam.height = opt.scout_height;
    cam.width = std::max(16, static_cast<int>(std::lround(opt.scout_height * tx / ty)));
    cam.near_m = opt.near_m;
    cam.far_m = opt.far_m;
    rig.coverage(cam, blocks, mask, &seen);
    const PinholeCamera pin = pinholeOf(cam);
    for (int y = 0; y < cam.height; ++y)
      for (int x = 0; x < cam.width; ++x) {
        if (!mask[size_t(y) * cam.width + x]) continue;
        const glm::dvec3 d = glm::normalize(pin.ray(x + 0.5, y + 0.5));
        rays.push_back({azimuthOf(d, heading_deg), d});
      }
  }
  return rays;
}

// The one-degree azimuth bin of `az` among the n bins from `lo`.
int azimuthBin(double az, double lo, int n) { return std::clamp(static_cast<int>(az - lo), 0, n - 1); }

// Rays to the outline points of the blocks the scout saw on fewer than
// scout_min_px pixels, inside the azimuth and elevation range.
void addOutlines(std::vector<CoveredRay>& rays, const glm::dvec3& eye_enu, double heading_deg, double az_lo,
                 double az_hi, const std::vector<uint32_t>& blocks, const std::vector<uint32_t>& seen,
                 const BlockOutlines& outlines, const CapturePlanOptions& opt) {
  const glm::dvec3 eye = render::enuToGltf(eye_enu);
  const double sin_lo = std::sin(glm::radians(opt.min_elevation_deg));
  const double sin_hi = std::sin(glm::radians(opt.max_elevation_deg));
  // One-degree azimuth bins within a bin of one the scout saw something in:
  // an outline point there only nudges a capture's edge.
  const int n = std::max(1, static_cast<int>(std::ceil(az_hi - az_lo)));
  std::vector<uint8_t> scouted(size_t(n), 0);
  for (const CoveredRay& r : rays) {
    const int b = azimuthBin(r.azimuth_deg, az_lo, n);
    for (int k = std::max(0, b - 1); k <= std::min(n - 1, b + 1); ++k) scouted[size_t(k)] = 1;
  }
  for (size_t i = 0; i < blocks.size(); ++i) {
    if (blocks[i] >= outlines.size()) continue;
    const bool barely = seen[i] < uint32_t(opt.scout_min_px);
    for (const glm::dvec3& p : outlines[blocks[i]]) {
      const glm::dvec3 v = render::enuToGltf(p) - eye;
      const double len = glm::length(v);
      if (len < opt.near_m || len > opt.far_m) continue;
      const glm::dvec3 d = v / len;
      const double az = azimuthOf(d, heading_deg);
      if (!(az >= az_lo && az <= az_hi && d.y >= sin_lo && d.y <= sin_hi)) continue;
      if (barely || (opt.outline_gaps && !scouted[size_t(azimuthBin(az, az_lo, n))])) rays.push_back({az, d});
    }
  }
}

// Covered azimuth intervals (degrees), split where no ray falls for more than
// kGapBins one-degree bins.
std::vector<std::pair<double, double>> coveredIntervals(const std::vector<CoveredRay>& rays, double lo, double hi) {
  const int n = std::max(1, static_cast<int>(std::ceil(hi - lo)));
  std::vector<uint8_t> bin(size_t(n), 0);
  for (const CoveredRay& r : rays) bin[size_t(azimuthBin(r.azimuth_deg, lo, n))] = 1;
  std::vector<std::pair<double, double>> out;
  int start = -1, last = -1;
  for (int i = 0; i <= n; ++i) {
    const bool on = i < n && bin[size_t(i)];
    if (on && start < 0) start = i;
    if (on) last = i;
    if (start >= 0 && (i == n || (!on && i - last > kGapBins))) {
      out.emplace_back(lo + start, std::min(hi, lo + last + 1.0));
      start = -1;
    }
  }
  return out;
}

// One capture fitted to `rays` (all inside one piece of azimuth).
CaptureShot fitOne(const std::vector<const CoveredRay*>& rays, const glm::dvec3& eye_enu, double heading_deg,
                   const CapturePlanOptions& opt) {
  double a0 = 1e9, a1 = -1e9, e0 = 1e9, e1 = -1e9;
  for (const CoveredRay* r : rays) {
    a0 = std::min(a0, r->azimuth_deg), a1 = std::max(a1, r->azimuth_deg);
    const double el = glm::degrees(std::asin(std::clamp(r->dir.y, -1.0, 1.0)));
    e0 = std::min(e0, el), e1 = std::max(e1, el);
  }
  render::Camera cam;
  cam.eye_enu = eye_enu;
  cam.heading_deg = heading_deg + 0.5 * (a0 + a1);
  cam.pitch_deg = std::clamp(0.5 * (e0 + e1), -80.0, 80.0);
  cam.near_m = opt.near_m;
  cam.far_m = opt.far_m;
  double tx = 0, ty = 0, sy0 = 0, sy1 = 0;
  for (int pass = 0; pass < 2; ++pass) {  // the second pass centres the pitch on the rays' image rows
    cam.fov_y_deg = 90.0, cam.width = cam.height = 64;
    const PinholeCamera pin = pinholeOf(cam);
    sy0 = 1e9, sy1 = -1e9;
    tx = 0;
    for (const CoveredRay* r : rays) {
      const double z = glm::dot(r->dir, pin.forward);
      if (z < 0.05) continue;
      tx = std::max(tx, std::abs(glm::dot(r->dir, pin.right) / z));
      const double sy = glm::dot(r->dir, pin.up) / z;
      sy0 = std::min(sy0, sy), sy1 = std::max(sy1, sy);
    }
    ty = std::max(std::abs(sy0), std::abs(sy1));
    if (pass == 0) cam.pitch_deg = std::clamp(cam.pitch_deg + glm::degrees(std::atan(0.5 * (sy0 + sy1))), -80.0, 80.0);
  }
  // margin_deg at the sides and below; above, less where the rays span
  // little height (capture_plan.h, thin_margin_deg). The pitch moves to the
  // middle of the rows so kept; at these few degrees the tangents shift by
  // well under the 2 % added.
  const double m = std::tan(glm::radians(opt.margin_deg));
  const double above =
      opt.thin_margin_deg > 0 ? std::min(m, std::max(ty, std::tan(glm::radians(opt.thin_margin_deg)))) : m;
  double half_y = ty + m;
  if (above < m && sy1 >= sy0) {
    const double lo = sy0 - m, hi = sy1 + above;
    cam.pitch_deg = std::clamp(cam.pitch_deg + glm::degrees(std::atan(0.5 * (lo + hi))), -80.0, 80.0);
    half_y = 0.5 * (hi - lo) * 1.02;
  }
  CaptureShot shot;
  shot.cam = cam;
  shot.tan_x = std::min(tx + m, std::tan(glm::radians(80.0)));
  shot.tan_y = std::min(half_y, std::tan(glm::radians(80.0)));
  sizeCapture(shot, 1.0, opt);
  return shot;
}

}  // namespace

// The most texels a capture may have each way: the layer atlas's side less
// its gutter on both sides, on the 4-texel grid.
int captureSideMax(const CapturePlanOptions& opt) { return std::max(16, (opt.texture_max - 2 * opt.gutter_px) / 4 * 4); }

void sizeCapture(CaptureShot& shot, double density, const CapturePlanOptions& opt) {
  const double tx = shot.tan_x, ty = shot.tan_y;
  const double W = 2 * tx * opt.display_ppr, H = 2 * ty * opt.display_ppr;
  const int side = captureSideMax(opt);
  shot.density = std::min(density, side / std::max(W, H));
  render::Camera& cam = shot.cam;
  cam.height = std::clamp(ceil4(H * shot.density), 16, side);
  cam.width = std::clamp(ceil4(cam.height * tx / ty), 16, side);
  // The rounded size keeps both half-fields covered.
  const double ty_eff = std::max(ty, tx * cam.height / cam.width);
  cam.fov_y_deg = 2.0 * glm::degrees(std::atan(ty_eff));
}

uint64_t fullDensityTexels(const CaptureShot& shot, const CapturePlanOptions& opt) {
  const double W = 2 * shot.tan_x * opt.display_ppr, H = 2 * shot.tan_y * opt.display_ppr;
  const double cap = std::min(1.0, captureSideMax(opt) / std::max(W, H));
  return uint64_t(W * cap * H * cap);
}

std::vector<CaptureShot> fitCaptures(const std::vector<CoveredRay>& rays, const glm::dvec3& eye_enu,
                                     double heading_deg, double az_lo_deg, double az_hi_deg,
                                     const CapturePlanOptions& opt) {
  std::vector<CaptureShot> shots;
  if (rays.empty()) return shots;
  for (const auto& [lo, hi] : coveredIntervals(rays, az_lo_deg, az_hi_deg)) {
    const int n = std::max(1, static_cast<int>(std::ceil((hi - lo) / opt.max_span_deg - 1e-9)));
    const double w = (hi - lo) / n;
    for (int i = 0; i < n; ++i) {
      const double p0 = lo + i * w, p1 = lo + (i + 1) * w;
      std::vector<const CoveredRay*> in;
      for (const CoveredRay& r : rays)
        if (r.azimuth_deg >= p0 && (r.azimuth_deg < p1 || (i + 1 == n && r.azimuth_deg <= p1))) in.push_back(&r);
      if (!in.empty()) shots.push_back(fitOne(in, eye_enu, heading_deg, opt));
    }
  }
  return shots;
}

std::vector<CaptureShot> planCaptures(CaptureRig& rig, const glm::dvec3& eye_enu, double heading_deg,
                                      double az_lo_deg, double az_hi_deg, const std::vector<uint32_t>& blocks,
                                      const CapturePlanOptions& opt, const BlockOutlines* outlines) {
  std::vector<uint32_t> seen;
  std::vector<CoveredRay> rays = scout(rig, eye_enu, heading_deg, az_lo_deg, az_hi_deg, blocks, opt, seen);
  if (outlines) addOutlines(rays, eye_enu, heading_deg, az_lo_deg, az_hi_deg, blocks, seen, *outlines, opt);
  return fitCaptures(rays, eye_enu, heading_deg, az_lo_deg, az_hi_deg, opt);
}

}  // namespace blvd::bake
