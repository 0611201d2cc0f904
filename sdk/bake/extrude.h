// Building prisms: a footprint extruded between min_height and height, with
// flat-shaded walls, a flat roof and (for raised parts) a bottom cap.
//
// Input is local metres (x = east, y = north, heights up); output goes into a
// geo::MeshData in glTF axes (geo::enuToGltf), triangles counter-clockwise
// seen from outside.
//
// Thread safety: no state; concurrent calls on different meshes are fine.
#pragma once
#include <cstdint>
#include <string>

#include "bake/triangulate.h"
#include "geo/mesh.h"

namespace blvd::bake {

// Appends the prism of `footprint` to `out`:
//  - walls: one quad per outline edge (collinear runs merged), own vertices
//    so the shading is flat, normals horizontal and pointing away from the
//    solid: outward on the outer ring, into the courtyard on inner rings;
//  - roof at `height`, normal up, triangulated by triangulate();
//  - bottom cap at `min_height`, normal down, only when min_height > 0
//    (building:part floating above ground, e.g. over an arcade).
// Walls and cap take wall_rgba, the roof roof_rgba (per-vertex sRGB).
// Ring winding in the input does not matter.
//
// Returns false with a reason, and appends nothing, when the footprint cannot
// be triangulated, a height is not finite, height <= min_height, or the mesh
// would exceed 32-bit indices. Never throws.
bool extrudeBuilding(const Polygon2& footprint, double min_height, double height,
                     const uint8_t wall_rgba[4], const uint8_t roof_rgba[4],
                     geo::MeshData& out, std::string& why);

// A wall colour for a building, fixed by its OSM id so every bake of the same
// data looks the same: one of a small Mediterranean palette (cream, ochre,
// salmon, light grey, white) with a slight brightness variation. Alpha 255.
void buildingColour(uint64_t osm_id, uint8_t rgba[4]);

// Roof colour for a wall colour: a few shades darker, so roofs read as a
// separate surface from above even though both are flat-shaded.
void roofColour(const uint8_t wall_rgba[4], uint8_t roof_rgba[4]);

}  // namespace blvd::bake
