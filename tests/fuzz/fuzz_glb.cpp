// Fuzz target for the GLB decoder (package::decodeGlb, and decodeGlbLevel on
// level 1 for MSFT_lod block blobs): any input must give
// Ok with a consistent mesh, or an error with a message; never a crash, a
// leak or undefined behaviour. A decoded mesh must also encode again.
//
// Seeds: set BLVD_FUZZ_SEED_DIR and the target writes a few GLBs of its own
// (plain, Draco, empty, projected texcoords) there before running; add tests/data/gltf as well.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "package/glb.h"

namespace {

blvd::geo::MeshData seedMesh() {
  blvd::geo::MeshData m;
  // Two triangles of a quad with normals and colours, plus a lone triangle.
  m.positions = {0, 0, 0, 1, 0, 0, 1, 0, -1, 0, 0, -1, 2, 0, 0, 3, 0, 0, 2, 1, 0};
  m.normals = {0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 0, 0, 1};
  m.colors.assign(7 * 4, 200);
  m.indices = {0, 1, 2, 0, 2, 3, 4, 5, 6};
  return m;
}

void writeSeed(const std::filesystem::path& dir, const char* name, const std::vector<uint8_t>& b) {
  std::ofstream f(dir / name, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  const char* dir = std::getenv("BLVD_FUZZ_SEED_DIR");
  if (!dir || !*dir) return 0;
  std::filesystem::create_directories(dir);
  blvd::package::GlbOptions plain;
  plain.codec = blvd::package::GlbCodec::Plain;
  writeSeed(dir, "seed_plain.glb", blvd::package::encodeGlb(seedMesh(), plain));
  writeSeed(dir, "seed_draco.glb", blvd::package::encodeGlb(seedMesh()));
  blvd::geo::MeshData bare = seedMesh();
  bare.normals.clear();
  bare.colors.clear();
  writeSeed(dir, "seed_bare_draco.glb", blvd::package::encodeGlb(bare));
  writeSeed(dir, "seed_empty.glb", blvd::package::encodeGlb(blvd::geo::MeshData{}));
  blvd::geo::MeshData textured = seedMesh();  // an impostor-like mesh: uvs + an embedded image
  for (size_t v = 0; v < textured.vertexCount(); ++v) textured.texcoords.insert(textured.texcoords.end(), {v * 0.1f, 1 - v * 0.1f});
  textured.image = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n', 0, 0, 0, 13};
  textured.image_mime = "image/png";
  writeSeed(dir, "seed_textured_draco.glb", blvd::package::encodeGlb(textured));
  writeSeed(dir, "seed_textured_plain.glb", blvd::package::encodeGlb(textured, plain));
  blvd::geo::MeshData lower = seedMesh();  // a block with a level of detail (MSFT_lod)
  lower.indices.resize(3);
  writeSeed(dir, "seed_levels_draco.glb", blvd::package::encodeGlbLevels({seedMesh(), lower}));
  blvd::package::GlbOptions meshopt;  // EXT_meshopt_compression (the default for block levels)
  meshopt.codec = blvd::package::GlbCodec::Meshopt;
  writeSeed(dir, "seed_meshopt.glb", blvd::package::encodeGlb(seedMesh(), meshopt));
  writeSeed(dir, "seed_levels_meshopt.glb", blvd::package::encodeGlbLevels({seedMesh(), lower}, meshopt));
  writeSeed(dir, "seed_textured_meshopt.glb", blvd::package::encodeGlb(textured, meshopt));
  meshopt.normal_bits = 8;
  meshopt.meshopt_position_bits = 0;
  writeSeed(dir, "seed_bare_meshopt.glb", blvd::package::encodeGlb(bare, meshopt));
  writeSeed(dir, "seed_snorm8_meshopt.glb", blvd::package::encodeGlb(seedMesh(), meshopt));
  // An impostor layer of two captures whose uv the decoder projects
  // (BLVD_projected_texcoords): orthographic projections, w = 1.
  blvd::package::TexcoordProjection proj;
  proj.shots.resize(2);
  proj.shots[0] = {{0.1f, 0, 0, 0.2f, 0, 0, -0.1f, 0.3f, 0, 0, 0, 1}, {0, 0, 0.5f, 1}};
  proj.shots[1] = {{0.05f, 0, 0, 0.4f, 0, 0.1f, 0, 0.1f, 0, 0, 0, 1}, {0.5f, 0, 1, 1}};
  proj.vertex_shot = {0, 0, 0, 0, 1, 1, 1};
  blvd::geo::MeshData layer = textured;
  layer.normals.clear();
  layer.colors.clear();
  for (size_t v = 0; v < layer.vertexCount(); ++v) {
    const float* m = proj.shots[proj.vertex_shot[v]].matrix;
    const float* p = &layer.positions[3 * v];
    for (int k = 0; k < 2; ++k) layer.texcoords[2 * v + k] = m[4 * k] * p[0] + m[4 * k + 1] * p[1] + m[4 * k + 2] * p[2] + m[4 * k + 3];
  }
  blvd::package::GlbOptions projected;
  projected.projection = &proj;
  writeSeed(dir, "seed_projected_draco.glb", blvd::package::encodeGlb(layer, projected));
  return 0;
}

namespace {
void checkOne(const uint8_t* data, size_t size, uint32_t level) {
  blvd::geo::MeshData mesh;
  std::string err;
  const blvd::core::Status s = blvd::package::decodeGlbLevel(data, size, level, mesh, err);
  if (s != blvd::core::Status::Ok) {
    if (err.empty() || !mesh.empty()) std::abort();  // every failure must say why, and leave nothing
    return;
  }
  // The decoder promises a consistent mesh; anything else is a bug.
  const size_t n = mesh.vertexCount();
  if (mesh.positions.size() != n * 3 || mesh.normals.size() != n * 3 || mesh.colors.size() != n * 4 ||
      (!mesh.texcoords.empty() && mesh.texcoords.size() != n * 2) || mesh.indices.size() % 3 != 0)
    std::abort();
  for (uint32_t i : mesh.indices)
    if (i >= n) std::abort();
  // And what it returns is valid input for the encoder (finite, in range).
  blvd::package::GlbOptions plain;
  plain.codec = blvd::package::GlbCodec::Plain;
  try {
    (void)blvd::package::encodeGlb(mesh, plain);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "re-encode failed: %s\n", e.what());
    std::abort();
  }
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  checkOne(data, size, 0);
  checkOne(data, size, 1);
  return 0;
}
