// Off-screen captures for the bake, through the same renderer and shading as
// the runtime: item buffers for visibility (Décoret 99 §5.3) and coverage
// (Marvie's ACH), and colour + depth images of a set of blocks for textured
// depth meshes (Sillion 97 §4.2).
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "bake/depth_mesh.h"
#include "geo/mesh.h"
#include "render/camera.h"
#include "render/context.h"
#include "render/renderer.h"

namespace blvd::bake {

class CaptureRig {
 public:
  // Uploads every block's mesh once (only those `draw` names, when not
  // empty; the others are never drawn). Throws core::Error(Backend) if no GL
  // context or renderer can be made.
  CaptureRig(const std::vector<geo::MeshData>& block_meshes, int max_width, int max_height,
             render::Backend backend = render::Backend::Auto, const std::vector<bool>& draw = {});
  ~CaptureRig();

  // Renders every block as its id (block + 1) and adds each block's pixel
  // count to counts[block] (counts is sized to the block count). With
  // `outline_counts` (sized alike), then, over that depth, the outlines of
  // the near-horizontal faces of each block no pixel centre fell on, as
  // lines, their pixels added there: a far ground strip or roof thinner than
  // a pixel gets the pixels its visible outline crosses, so the PVS keeps
  // what shows at display resolution (docs/decisions/0036).
  void itemBuffer(const render::Camera& cam, std::vector<uint32_t>& counts,
                  std::vector<uint32_t>* outline_counts = nullptr);

  // Which pixels of `cam` show any of `blocks` (mask: width * height, top
  // row first, 1 = covered). An item-buffer pass; with `counts` (sized to
  // blocks), each block's pixels are added to counts[its index in blocks].
  void coverage(const render::Camera& cam, const std::vector<uint32_t>& blocks, std::vector<uint8_t>& mask,
                std::vector<uint32_t>* counts = nullptr);

  // Colour (lit, unfogged) and view depth of `blocks` only, as seen by `cam`.
  // Also fills `pinhole` with the matching camera for depth-mesh building.
  void capture(const render::Camera& cam, const std::vector<uint32_t>& blocks, CaptureImage& out,
               PinholeCamera& pinhole);

  // Whether `eye_enu` lies inside a building: looking straight up, the
  // first surface is a back face (a roof seen from below).
  bool insideGeometry(const glm::dvec3& eye_enu);

  const char* backendName() const { return ctx_->name(); }
  size_t blockCount() const { return handles_.size(); }

 private:
  // Draws list_ with ids_ in an item-buffer pass and reads it into pixels_
  // (keep_depth: over the last pass's depth, RenderOptions::keep_depth).
  void drawIds(const render::Camera& cam, const char* what, bool keep_depth = false);
  void listBlocks(const std::vector<render::MeshHandle>& meshes, const std::vector<uint32_t>* skip = nullptr);
  // Adds the pixels of each id (1-based) in the first n of pixels_ to counts[id - 1].
  void addIdCounts(size_t n, std::vector<uint32_t>& counts) const;

  std::unique_ptr<render::Context> ctx_;
  std::unique_ptr<render::Renderer> renderer_;
  std::vector<render::MeshHandle> handles_;  // per block (id 0 when empty)
  std::vector<render::MeshHandle> outlines_; // per block, its lines (outlineLines; id 0: none)
  std::vector<uint32_t> view_counts_;
  std::vector<render::MeshHandle> list_;
  std::vector<uint32_t> ids_;
  std::vector<uint8_t> pixels_, depth_pixels_;
  int max_w_, max_h_;
};

// The edges of `mesh` that bound its near-horizontal faces (ground, streets,
// roofs: each edge one such triangle has and no other), as line pairs over
// the vertices they use. Sorted, so the same mesh gives the same lines.
geo::MeshData outlineLines(const geo::MeshData& mesh);

// The pinhole model of a render::Camera (glTF axes), for depth_mesh.
PinholeCamera pinholeOf(const render::Camera& cam);

}  // namespace blvd::bake
