// Fidelity of the far city, measured where it is: the pixels where the full
// model shows a block that is not in the cell's local model (the far mask),
// compared with what a render mode draws there and around it.
//
// Inputs per pose, all w*h, top row first:
//   - ref_rgba, test_rgba: the full model's frame and the mode's frame (RGBA8);
//   - ref_items: the full model's object-id buffer (blvd_read_items): block + 1
//     where a block shows, 0 for sky and ground;
//   - test_items: the mode's object-id buffer: block + 1 for geometry,
//     BLVD_ITEM_IMPOSTOR | (layer + 1) for an impostor layer, 0 for nothing;
//   - is_local(block): the cell's local model;
//   - layer_holds(layer, block): impostor layer `layer` (0-based, in the
//     order drawn) stands for far block `block`.
//
// Definitions (the bench's JSON keys, docs/benchmarks.md):
//   far mask F      ref_items shows a non-local block;
//   drawn far D     test_items shows an impostor or a non-local block;
//   far_bad         |{p in F : pixelError(ref, test) > 10 %}| / |F| (of the far region);
//   holes           |{p in F : p not in D}| / (w*h);
//   spurious        |{p not in F : p in D, pixelError > 10 %, and farther than
//                   edge_tolerance_px from F}| / (w*h): rubber sheets and needles,
//                   not a silhouette a pixel off (that is the visibility error);
//   missing objects far blocks with >= 200 pixels in F whose pixels show what
//                   stands for them (their layer, or themselves as geometry)
//                   on fewer than half of them;
//   visibility error what Décoret 99 bounds (§4: "how A and B can move
//                   relative to each other in the image"; §6.1: "a maximum
//                   error of 10 pixels"): the size, in display pixels, of a
//                   region where far visibility is wrong. E is where F and D disagree (a
//                   far block not drawn, or drawn where none shows); each E
//                   pixel's thickness is the shorter of E's horizontal and
//                   vertical runs through it. Each boundary pixel of F and of
//                   D (a pixel whose 4-neighbour is on the other side, the
//                   image border not counting) takes the largest thickness of
//                   E at it or its 4-neighbours, 0 where the two silhouettes
//                   agree; the error is the 95th percentile. A silhouette
//                   shifted by k px measures k, a crack between layers its
//                   width, a missing block its smaller extent.
//   silhouette distance the same boundary pixels' Euclidean distance to the
//                   nearest boundary pixel of the other image (both ways,
//                   exact distance transform), 95th percentile. A crack inside
//                   F counts here by its distance to F's outline.
//
// Pure functions; thread-safe; allocate scratch of O(w*h).
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

namespace blvd::cli {

// The id bit of an impostor layer in an object-id buffer (BLVD_ITEM_IMPOSTOR).
constexpr uint32_t kItemImpostor = 0x800000u;

struct FarInputs {
  int w = 0, h = 0;
  const uint8_t* ref_rgba = nullptr;
  const uint8_t* test_rgba = nullptr;
  const uint32_t* ref_items = nullptr;
  const uint32_t* test_items = nullptr;
  std::function<bool(uint32_t block)> is_local;
  std::function<bool(uint32_t layer, uint32_t block)> layer_holds;  // may be empty: no impostors
  double threshold = 0.10;        // colour error of a bad pixel (imaging::pixelError)
  int edge_tolerance_px = 2;      // spurious pixels this close to F are silhouette error
  uint32_t min_object_px = 200;   // missing objects: blocks at least this large in F
};

// What a mode shows on a missing object's pixels: why it is missing.
struct MissingObject {
  uint32_t block = 0;
  uint32_t px = 0;           // its pixels in F
  uint32_t own = 0;          // shown by what stands for it
  uint32_t other_layer = 0;  // covered by an impostor layer that does not hold it
  uint32_t geometry = 0;     // covered by another block's geometry
  uint32_t nothing = 0;      // sky or ground: no layer drew there
  uint32_t bad = 0;          // of its pixels, those whose colour is off (a driver sees these)
};

struct FarMetrics {
  uint64_t far_px = 0;            // |F|
  double far_bad = 0;             // share of F
  double holes = 0;               // share of the frame
  double spurious = 0;            // share of the frame
  uint32_t missing_objects = 0;
  std::vector<uint32_t> missing;  // their block ids
  std::vector<MissingObject> missing_shown;  // the same blocks, what shows on their pixels
  double visibility_error_px = 0; // 95th percentile of the wrong region's thickness at the silhouettes
  double silhouette_distance_px = 0;  // 95th percentile of boundary-to-boundary distance
  uint64_t silhouette_px = 0;     // boundary pixels of F
  // Per pixel, for the error overlay: 0 outside F and fine, 1 in F and
  // fine, 2 in F and bad or a hole, 3 spurious.
  std::vector<uint8_t> classes;
};

FarMetrics measureFar(const FarInputs& in);

// The error overlay of the worst-frames gallery, RGBA8 w*h into `out`: the
// reference dimmed to grey, the far mask tinted blue, wrong far pixels and
// holes red, spurious pixels magenta.
void farOverlay(const uint8_t* ref_rgba, const FarMetrics& m, int w, int h, uint8_t* out);

// Squared Euclidean distance of every pixel to the nearest set pixel of
// `seed` (Felzenszwalb & Huttenlocher 2012, the 1-D lower envelope of
// parabolas along rows, then columns). Pixels with no seed anywhere get
// +infinity. Exposed for tests.
std::vector<float> distanceTransform2(const std::vector<uint8_t>& seed, int w, int h);

}  // namespace blvd::cli
