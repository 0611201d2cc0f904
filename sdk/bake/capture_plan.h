// Where a cell's impostor captures look, and at what resolution.
//
// Sillion 97 §4.2 captures the far model with one frustum "looking down the
// street"; Kmoch 06 §4.4.4 places the camera and cuts its sides to what the
// impostor must show. A street that bends needs more than one planar frustum
// can hold undistorted, and a layer's blocks cover only part of any frustum,
// so the rule here is (docs/decisions/0010):
//
//  1. The azimuths a viewer anywhere along the cell can look at, seen from
//     the vantage point: every heading the street takes, plus half the
//     display's field and a margin on each side (up to the full circle).
//  2. A scout render of the layer's blocks over that range (low resolution,
//     -50° to +80° of elevation) tells which directions the blocks really
//     cover: geometry, not bounding boxes (a large block whose box corners are
//     far may hold a building beside the vantage point).
//     A block the scout sees on fewer than `scout_min_px` pixels (a far
//     ground strip thinner than a scout row, seen edge-on) is added by its
//     outline: points along its ground footprint, as rays from the eye. So
//     are the outline points of any block in azimuths where the scout found
//     nothing of the layer within a degree (the strip of a large block that
//     the scout saw elsewhere; decision 0034).
//  3. The covered azimuths, split at gaps, are cut into pieces of at most
//     `max_span_deg`, and each piece gets one planar capture fitted to the
//     covered rays inside it (heading, pitch and both half-fields, plus a
//     margin: margin_deg at the sides and below, less above far low
//     content, decision 0035), so no capture is wider than a display and
//     none is stretched by a wide-angle projection.
//  4. Each capture is sized for one texel per display pixel at the vantage
//     point (the display's pixels per radian at its centre), scaled down to
//     `texture_max` on its longer side where that caps it, and all of a
//     cell's captures together scaled down to the cell's texel budget (the
//     package's size); the density kept is reported.
#pragma once
#include <cstdint>
#include <vector>

#include "bake/capture.h"
#include "bake/street_points.h"
#include "render/camera.h"

namespace blvd::bake {

struct CapturePlanOptions {
  double max_span_deg = 45.0;       // widest piece of azimuth one capture holds
  int texture_max = 512;            // longest texture side
  int gutter_px = 0;                // kept clear round each capture in its layer's atlas (of texture_max)
  double display_ppr = 579.4;       // display pixels per unit of tan at its centre (800x480, 45°)
  double margin_deg = 1.5;          // added around the covered directions
  // Above its rays, a capture whose rays span less than margin_deg each way
  // from their middle (far ground, a low row of far blocks) gets a margin of
  // that half-span, and at least this (0: margin_deg all round). Its rows
  // then fall on what it shows: a far ground strip 0.15° tall had a 16-row
  // capture 3.1° tall, and fell between its rows. Above far low content lie
  // its far edge and the sky, whose elevation barely changes along a run;
  // below, the near ground drops down the view as the viewer drives on
  // (at eye height h, ground d metres away is atan(h / d) below the
  // horizon), so the margin there stays margin_deg (decision 0035).
  double thin_margin_deg = 0.25;
  double min_elevation_deg = -50.0, max_elevation_deg = 80.0;  // the scout's vertical reach
  // Rows of a scout view: at 256 (0.51° a row) a far block's ground seen
  // edge-on and thin far blocks fell between rows, their directions went
  // uncaptured, and twice as many poses missed a block (decision 0015).
  int scout_height = 512;
  // A block the scout sees on fewer pixels than this is covered by its
  // outline. At 32 (of 0, 8, 32, 128 and every block measured) San Francisco's
  // poses missing a far block fell from 36 to 25 (decision 0015).
  int scout_min_px = 32;
  // Also add any block's outline points in azimuths the scout found empty
  // (on the 2016 route and San Francisco: missing-object poses 2 -> 1 and
  // 18 -> 15, decision 0034).
  bool outline_gaps = true;
  double near_m = 0.5, far_m = kViewDistanceM;
};

struct CaptureShot {
  render::Camera cam;
  double density = 1.0;  // texels per display pixel at the capture's centre (< 1: a cap bit)
  double tan_x = 0, tan_y = 0;  // the half-fields the capture must hold (tangents)
};

// Sizes a capture for `density` texels per display pixel at its centre (at
// most 1, and less where its longer side would pass texture_max less the
// gutter on both sides): width, height and the vertical field that keeps
// both half-fields inside.
void sizeCapture(CaptureShot& shot, double density, const CapturePlanOptions& opt);

// Texels of the capture at one texel per display pixel (or at the side cap).
uint64_t fullDensityTexels(const CaptureShot& shot, const CapturePlanOptions& opt);

// Per block id, points (ENU) along its ground footprint: what the planner
// looks at where the scout misses a block (empty: none).
using BlockOutlines = std::vector<std::vector<glm::dvec3>>;

// Captures for `blocks` from `eye_enu`, covering azimuths [az_lo_deg,
// az_hi_deg] relative to `heading_deg` (clockwise positive; the span at most
// 360°). Empty when the blocks cover nothing in that range.
std::vector<CaptureShot> planCaptures(CaptureRig& rig, const glm::dvec3& eye_enu, double heading_deg,
                                      double az_lo_deg, double az_hi_deg, const std::vector<uint32_t>& blocks,
                                      const CapturePlanOptions& opt, const BlockOutlines* outlines = nullptr);

// One covered direction as the planner sees it (exposed for tests).
struct CoveredRay {
  double azimuth_deg;  // relative to the reference heading, clockwise positive
  glm::dvec3 dir;      // unit, glTF axes
};

// Step 3 and 4 on given rays: the pieces and their cameras.
std::vector<CaptureShot> fitCaptures(const std::vector<CoveredRay>& rays, const glm::dvec3& eye_enu,
                                     double heading_deg, double az_lo_deg, double az_hi_deg,
                                     const CapturePlanOptions& opt);

}  // namespace blvd::bake
