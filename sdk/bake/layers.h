// Multi-layer impostors: grouping the far objects of a viewing cell into
// layers (Décoret, Schaufler, Sillion, Dorsey 1999, §4.1–4.2).
//
// Two objects belong in the same layer only if the visibility events between
// them, seen from anywhere on the cell's segment [PQ], stay below a threshold
// T: then one textured depth mesh can show both without visible parallax
// errors. The importance of the events between two objects is the variation of
// the angle under which a point of one and a point of the other are seen from
// M ∈ [PQ] (D99 §4.1), computed on the ground plane for extruded buildings and
// a segment viewing cell, exactly the paper's restricted case.
#pragma once
#include <cstdint>
#include <vector>

#include <glm/vec2.hpp>

namespace blvd::bake {

// max over M ∈ [PQ] of angle AMB minus its min (radians), by the paper's
// closed-form extremal positions (equations 3–5, or H when AB ∥ PQ) plus the
// segment ends. A point on the line PQ itself gives π (it can be seen on
// either side: the worst case).
double angleVariation(glm::dvec2 P, glm::dvec2 Q, glm::dvec2 A, glm::dvec2 B);

struct LayerObject {
  uint32_t id = 0;
  std::vector<glm::dvec2> hull;  // convex footprint on the ground plane (east, north), CCW
  double weight_scale = 1.0;     // > 1 raises a landmark's weights (D99 §4.2)
};

// Convex hull (Andrew's monotone chain), CCW, without repeated points.
std::vector<glm::dvec2> convexHull(std::vector<glm::dvec2> pts);

// w_ij of D99 §4.2: 0 when neither object meets the other's critical zone
// (the convex hull of the object and [PQ], §4.1), else the largest
// angleVariation over pairs of hull points (at most `max_points` per object,
// evenly taken), times the larger weight_scale.
double objectWeight(glm::dvec2 P, glm::dvec2 Q, const LayerObject& a, const LayerObject& b, size_t max_points = 8);

struct LayerAssignment {
  std::vector<std::vector<uint32_t>> layers;  // object indices (into the input), per layer
  std::vector<double> weights;                // n*n matrix w_ij, row-major
};

// The greedy colouring of D99 §4.2: objects are taken nearest-first; each goes
// into an existing layer whose edges to it all weigh ≤ threshold_rad,
// choosing among several the one whose bounding box (with the object) has the
// smallest area; otherwise it opens a new layer.
LayerAssignment assignLayers(glm::dvec2 P, glm::dvec2 Q, const std::vector<LayerObject>& objects,
                             double threshold_rad);

// Caps the layer count at `max_layers` by dropping, one at a time, the last
// layer and moving each of its objects into the layer whose largest weight to
// that object is smallest (the move that adds the least visibility-event
// error for it; decision 0037). Returns the largest weight a move admitted
// (0 when nothing had to merge).
double capLayers(LayerAssignment& la, size_t n_objects, size_t max_layers);

// The threshold T given in pixels at a display of `width_px` pixels across a
// horizontal field of view of `fov_x_deg`, in radians (D99 §6 uses 10 px at 512²).
double pixelsToRadians(double pixels, double width_px, double fov_x_deg);

}  // namespace blvd::bake
