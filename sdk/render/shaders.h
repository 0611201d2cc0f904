// GLSL sources, written once for GLSL ES 3.00 and GLSL 3.30 core: the
// renderer prefixes one #version line and the common prelude. Both dialects
// accept `precision` qualifiers and explicit attribute/output locations.
#pragma once

namespace blvd::render::shaders {

extern const char* const kVersionEs;    // "#version 300 es\n"
extern const char* const kVersionCore;  // "#version 330 core\n"
extern const char* const kPrelude;      // precision, look uniforms, fog and output helpers

// Full-screen triangle: sky gradient above the horizon, the lit ground plane
// y = 0 below it (ray-plane intersection per pixel, fogged by distance).
extern const char* const kBackgroundVs;
extern const char* const kBackgroundFs;

// City meshes: Lambert sun + hemispheric ambient on the vertex colour,
// distance fog towards the horizon colour.
extern const char* const kMeshVs;
extern const char* const kMeshFs;

// Bake capture passes over kMeshVs: item buffer (flat id colour), lit colour
// without fog (undersides marked), view depth packed into RGB.
extern const char* const kItemFs;
extern const char* const kCaptureColorFs;
extern const char* const kCaptureDepthFs;

// Textured depth meshes (impostors): the baked colour, fogged at draw time.
extern const char* const kTexturedVs;
extern const char* const kTexturedFs;
extern const char* const kUpscaleVs;
extern const char* const kUpscaleFs;

}  // namespace blvd::render::shaders
