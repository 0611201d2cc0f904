// Slab uploads in chunks (a frame's GL uploads stay within its
// budget): the mip chain is made on the preparing thread, an upload spread
// over many small steps draws the same picture as one copied whole, and a
// slab reset abandons an unfinished upload. A slab mesh copied GPU-side into
// another slab (a block two cells share) draws what the original draws.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "render/atlas_etc2.h"
#include "render/context.h"
#include "render/gl_api.h"
#include "render/prepared_mesh.h"
#include "render/renderer.h"
#include "scene.h"
#include <stb/stb_image_write.h>
#include <webp/encode.h>

namespace blvd::render {
namespace {

constexpr int kW = 160, kH = 120;

// PNG bytes of a w × h RGBA image, as a glTF would embed them.
std::vector<uint8_t> png(const std::vector<uint8_t>& rgba, int w, int h) {
  std::vector<uint8_t> out;
  stbi_write_png_to_func(
      [](void* ctx, void* data, int size) {
        auto* v = static_cast<std::vector<uint8_t>*>(ctx);
        v->insert(v->end(), static_cast<uint8_t*>(data), static_cast<uint8_t*>(data) + size);
      },
      &out, w, h, 4, rgba.data(), w * 4);
  return out;
}

// A WebP texture (lossless here, so every texel is known) decodes straight
// into the staging arena, as the top of its mip chain.
TEST(MipChain, WebpTexturesDecodeIntoTheArena) {
  geo::MeshData m = test::makeFlat(0, 0, 1, 1, 0, std::array<uint8_t, 4>{255, 255, 255, 255}.data());
  m.texcoords = {0, 0, 1, 0, 1, 1, 0, 1};
  std::vector<uint8_t> texels(6 * 4 * 4, 255);
  for (int i = 0; i < 24; ++i) texels[size_t(i) * 4] = uint8_t(i * 10), texels[size_t(i) * 4 + 1] = uint8_t(255 - i);
  uint8_t* webp = nullptr;
  const size_t n = WebPEncodeLosslessRGBA(texels.data(), 6, 4, 6 * 4, &webp);
  ASSERT_GT(n, 0u);
  m.image.assign(webp, webp + n);
  WebPFree(webp);
  m.image_mime = "image/webp";
  std::vector<uint8_t> block(preparedBytes(4, 6, 6, 4));
  StagingArena arena{block.data(), block.size(), 0};
  PreparedMesh p;
  std::string err;
  ASSERT_TRUE(prepareMesh(m, arena, p, err)) << err;
  EXPECT_EQ(p.texture_width, 6);
  EXPECT_EQ(p.texture_height, 4);
  EXPECT_EQ(p.mip_levels, 3);
  EXPECT_TRUE(std::equal(texels.begin(), texels.end(), p.rgba));
  // Bytes that only look like WebP are refused, not drawn.
  m.image.resize(20);
  arena.used = 0;
  EXPECT_FALSE(prepareMesh(m, arena, p, err));
  EXPECT_EQ(err, "mesh image cannot be decoded");
}

TEST(MipChain, BoxFiltersEachLevelFromTheOneAbove) {
  int levels = 0;
  EXPECT_EQ(mipChainBytes(4, 2, &levels), uint64_t(4 * 2 + 2 * 1 + 1 * 1) * 4);
  EXPECT_EQ(levels, 3);
  EXPECT_EQ(mipChainBytes(1024, 640, &levels), [] {
    uint64_t b = 0;
    for (int w = 1024, h = 640;; w = std::max(1, w / 2), h = std::max(1, h / 2)) {
      b += uint64_t(w) * h * 4;
      if (w == 1 && h == 1) return b;
    }
  }());
  EXPECT_EQ(levels, 11);

  // A 4 × 2 textured quad whose red channel counts 0, 40, ..., 280 % 256.
  geo::MeshData m = test::makeFlat(0, 0, 1, 1, 0, std::array<uint8_t, 4>{255, 255, 255, 255}.data());
  m.texcoords = {0, 0, 1, 0, 1, 1, 0, 1};
  std::vector<uint8_t> texels(4 * 2 * 4, 255);
  for (int i = 0; i < 8; ++i) texels[size_t(i) * 4] = uint8_t(i * 30);
  m.image = png(texels, 4, 2);
  ASSERT_FALSE(m.image.empty());

  std::vector<uint8_t> block(preparedBytes(4, 6, 4, 2));
  StagingArena arena{block.data(), block.size(), 0};
  PreparedMesh p;
  std::string err;
  ASSERT_TRUE(prepareMesh(m, arena, p, err)) << err;
  ASSERT_EQ(p.mip_levels, 3);
  int w = 0, h = 0;
  const uint8_t* l1 = mipLevel(p, 1, w, h);
  ASSERT_NE(l1, nullptr);
  EXPECT_EQ(w, 2);
  EXPECT_EQ(h, 1);
  // Texel (0, 0) of level 1 is the rounded mean of (0,0), (1,0), (0,1), (1,1).
  EXPECT_EQ(l1[0], (0 + 30 + 120 + 150 + 2) / 4);
  EXPECT_EQ(l1[4], (60 + 90 + 180 + 210 + 2) / 4);
  const uint8_t* l2 = mipLevel(p, 2, w, h);
  EXPECT_EQ(w * h, 1);
  EXPECT_EQ(l2[0], (l1[0] + l1[4] + l1[0] + l1[4] + 2) / 4);
  EXPECT_EQ(mipLevel(p, 3, w, h), nullptr);
}

// A street of boxes (tens of kilobytes of vertices) and a textured wall.
struct Scene {
  std::vector<geo::MeshData> meshes;
  Scene() {
    const uint8_t grey[4] = {150, 150, 160, 255};
    geo::MeshData boxes;
    for (int i = 0; i < 60; ++i) {
      const geo::MeshData b = test::makeBox(float(i % 2 ? 6 : -6), 2.f, -float(8 + 4 * (i / 2)), 3.f, 4.f + float(i % 5),
                                            3.f, grey);
      const auto base = static_cast<uint32_t>(boxes.vertexCount());
      boxes.positions.insert(boxes.positions.end(), b.positions.begin(), b.positions.end());
      boxes.normals.insert(boxes.normals.end(), b.normals.begin(), b.normals.end());
      boxes.colors.insert(boxes.colors.end(), b.colors.begin(), b.colors.end());
      for (uint32_t k : b.indices) boxes.indices.push_back(base + k);
    }
    meshes.push_back(boxes);
    // A 256 × 128 striped texture on a wall across the far end.
    geo::MeshData wall;
    wall.positions = {-20, 0, -150, 20, 0, -150, 20, 30, -150, -20, 30, -150};
    wall.texcoords = {0, 0, 1, 0, 1, 1, 0, 1};
    wall.indices = {0, 1, 2, 0, 2, 3};
    std::vector<uint8_t> texels(256 * 128 * 4);
    for (int y = 0; y < 128; ++y)
      for (int x = 0; x < 256; ++x) {
        uint8_t* t = &texels[(size_t(y) * 256 + x) * 4];
        t[0] = uint8_t((x / 16) % 2 ? 220 : 40), t[1] = uint8_t(y * 2), t[2] = 90, t[3] = 255;
      }
    wall.image = png(texels, 256, 128);
    meshes.push_back(wall);
  }
};

struct Prepared {
  std::vector<uint8_t> block;
  std::vector<PreparedMesh> meshes;
  explicit Prepared(const Scene& s) {
    size_t bytes = 0;
    for (const auto& m : s.meshes) bytes += preparedBytes(m.vertexCount(), m.indices.size(), 256, 128);
    block.resize(bytes);
    StagingArena arena{block.data(), block.size(), 0};
    for (const auto& m : s.meshes) {
      PreparedMesh p;
      std::string err;
      EXPECT_TRUE(prepareMesh(m, arena, p, err)) << err;
      if (p.rgba) p.atlas_x = p.atlas_y = 0;  // alone in its slab's atlas
      meshes.push_back(p);
    }
  }
};

SlabDesc slabFor(const Prepared& p) {
  SlabDesc d;
  for (const PreparedMesh& m : p.meshes) {
    d.vertex_bytes += m.vertexBytes();
    d.index_bytes += m.indexBytes() + 3;
  }
  d.meshes = 4;
  d.atlas_width = 512;  // larger than the image: it lands in a corner
  d.atlas_height = 256;
  return d;
}

// A context and a renderer of kW × kH.
struct Rig {
  std::string why;
  std::unique_ptr<Context> ctx = createContext(Backend::Auto, why);
  std::unique_ptr<Renderer> renderer;
  Rig() {
    RendererDesc desc;
    desc.width = kW;
    desc.height = kH;
    if (ctx) renderer = Renderer::create(*ctx, desc, why);
  }
};

Camera viewCamera() {
  Camera cam;
  cam.eye_enu = {0.0, 0.0, 2.0};
  cam.width = kW;
  cam.height = kH;
  return cam;
}

// The frame of `list` seen from `back` metres behind the view camera.
std::vector<uint8_t> draw(Renderer& r, const std::vector<MeshHandle>& list, double back = 0) {
  Camera cam = viewCamera();
  cam.eye_enu.y = back;
  EXPECT_TRUE(r.render(cam, list.data(), list.size(), nullptr)) << r.lastError();
  std::vector<uint8_t> px(size_t(kW) * kH * 4);
  EXPECT_TRUE(r.readPixels(px.data()));
  return px;
}

// Finishes a begun upload or copy in steps of max_bytes; a step before the
// last returns no handle.
MeshHandle finishInSteps(Renderer& r, SlabUpload& up, uint64_t max_bytes, int& steps) {
  bool finished = false;
  MeshHandle h;
  while (!finished) {
    h = r.continueSlabUpload(up, max_bytes, finished);
    ++steps;
    if (!finished) {
      EXPECT_EQ(h.id, 0u);
    }
  }
  return h;
}

TEST(SlabUpload, ManySmallStepsDrawWhatOneCopyDraws) {
  Rig rig;
  ASSERT_NE(rig.renderer, nullptr) << rig.why;
  Renderer* r = rig.renderer.get();
  const Scene scene;
  const Prepared prep(scene);
  ASSERT_GT(prep.meshes[0].vertexBytes(), 20000u);  // several 4 KiB chunks

  const SlabHandle whole = r->createSlab(slabFor(prep));
  std::vector<MeshHandle> once;
  for (const PreparedMesh& m : prep.meshes) once.push_back(r->uploadToSlab(whole, m));
  for (MeshHandle h : once) ASSERT_NE(h.id, 0u) << r->lastError();
  const std::vector<uint8_t> a = draw(*r, once);

  const SlabHandle stepped = r->createSlab(slabFor(prep));
  std::vector<MeshHandle> chunked;
  int steps = 0;
  for (const PreparedMesh& m : prep.meshes) {
    SlabUpload up;
    ASSERT_TRUE(r->beginSlabUpload(stepped, m, up)) << r->lastError();
    const MeshHandle h = finishInSteps(*r, up, 1, steps);  // the smallest chunk: 4 KiB or one texture row
    ASSERT_NE(h.id, 0u) << r->lastError();
    chunked.push_back(h);
  }
  // At most 4 KiB (or one texture row, if longer) a step; an atlas takes an
  // image's first kAtlasLevels levels.
  uint64_t total = 0;
  for (const PreparedMesh& m : prep.meshes) {
    total += m.vertexBytes() + m.indexBytes();
    for (int l = 0; m.rgba && l < kAtlasLevels; ++l) {
      int w = 0, h = 0;
      mipLevel(m, l, w, h);
      total += uint64_t(w) * uint64_t(h) * 4;
    }
  }
  EXPECT_GE(uint64_t(steps), total / 4096);
  const std::vector<uint8_t> b = draw(*r, chunked);
  EXPECT_EQ(a, b) << "a mesh copied in steps draws differently";
  // The wall is really there: the stripes differ from the sky around them.
  int red = 0;
  for (size_t i = 0; i < b.size(); i += 4) red += b[i] > 150 && b[i + 2] < 120;
  EXPECT_GT(red, 10);
}

// A textured wall `tw` x `th` (no power of two), far away so that it is drawn
// from the coarse mip levels, with each texel's colour from `texel`.
template <typename F>
geo::MeshData farWall(int tw, int th, F texel) {
  geo::MeshData wall;
  wall.positions = {-30, 0, -260, 30, 0, -260, 30, 40, -260, -30, 40, -260};
  wall.texcoords = {0, 0, 1, 0, 1, 1, 0, 1};
  wall.indices = {0, 1, 2, 0, 2, 3};
  std::vector<uint8_t> texels(size_t(tw) * th * 4);
  for (int y = 0; y < th; ++y)
    for (int x = 0; x < tw; ++x) texel(x, y, &texels[(size_t(y) * tw + x) * 4]);
  wall.image = png(texels, tw, th);
  return wall;
}

// A slab's atlas keeps what earlier images left outside the current image's
// place; filtering the image's coarse levels must not reach it (the frames of
// a runtime then depended on which cells its slots had held: SlotHistory.*).
TEST(SlabUpload, AnImageIsNotBledIntoByWhatItsTextureHeldBefore) {
  Rig rig;
  ASSERT_NE(rig.renderer, nullptr) << rig.why;
  Renderer* r = rig.renderer.get();
  const geo::MeshData big = farWall(512, 256, [](int, int, uint8_t* t) { t[0] = 255, t[1] = 0, t[2] = 255, t[3] = 255; });
  const geo::MeshData small = farWall(203, 117, [](int x, int y, uint8_t* t) {
    t[0] = uint8_t(40 + (x * 7) % 60), t[1] = uint8_t(60 + (y * 5) % 80), t[2] = 70, t[3] = 255;
  });
  std::vector<uint8_t> block(preparedBytes(4, 6, 512, 256) + preparedBytes(4, 6, 203, 117));
  StagingArena arena{block.data(), block.size(), 0};
  PreparedMesh pb, ps;
  std::string err;
  ASSERT_TRUE(prepareMesh(big, arena, pb, err)) << err;
  ASSERT_TRUE(prepareMesh(small, arena, ps, err)) << err;
  pb.atlas_x = pb.atlas_y = ps.atlas_x = ps.atlas_y = 0;
  SlabDesc d;
  d.vertex_bytes = 2 * pb.vertexBytes();
  d.index_bytes = 2 * pb.indexBytes() + 8;
  d.meshes = 2;
  d.atlas_width = 512;
  d.atlas_height = 256;
  const SlabHandle fresh = r->createSlab(d), used = r->createSlab(d);
  // The used slab's texture held a magenta image of its full size first.
  ASSERT_NE(r->uploadToSlab(used, pb).id, 0u) << r->lastError();
  r->resetSlab(used);
  const MeshHandle a = r->uploadToSlab(fresh, ps);
  int steps = 0;
  SlabUpload up;
  ASSERT_TRUE(r->beginSlabUpload(used, ps, up)) << r->lastError();
  const MeshHandle b = finishInSteps(*r, up, 1, steps);
  ASSERT_NE(a.id, 0u) << r->lastError();
  ASSERT_NE(b.id, 0u) << r->lastError();
  const std::vector<uint8_t> fa = draw(*r, {a}), fb = draw(*r, {b});
  int wall = 0, magenta = 0;
  for (size_t i = 0; i < fb.size(); i += 4) {
    wall += fa[i + 2] == 70 || (fa[i] < 110 && fa[i + 1] > 50 && fa[i + 2] < 90);
    magenta += fb[i] > 150 && fb[i + 1] < 100 && fb[i + 2] > 150;
  }
  EXPECT_GT(wall, 20) << "the wall is not in the frame";
  EXPECT_EQ(magenta, 0);
  EXPECT_TRUE(fa == fb) << "the image drawn from a texture that held another one differs";
}

TEST(SlabUpload, AResetAbandonsAnUnfinishedUpload) {
  Rig rig;
  ASSERT_NE(rig.renderer, nullptr) << rig.why;
  Renderer* r = rig.renderer.get();
  const Scene scene;
  const Prepared prep(scene);
  const SlabHandle slab = r->createSlab(slabFor(prep));
  SlabUpload up;
  ASSERT_TRUE(r->beginSlabUpload(slab, prep.meshes[0], up));
  bool finished = true;
  EXPECT_EQ(r->continueSlabUpload(up, 1, finished).id, 0u);
  EXPECT_FALSE(finished);
  r->resetSlab(slab);
  EXPECT_EQ(r->continueSlabUpload(up, 1 << 20, finished).id, 0u);
  EXPECT_TRUE(finished);
  EXPECT_NE(r->lastError().find("abandoned"), std::string::npos) << r->lastError();
  EXPECT_EQ(r->meshCount(), 0u);
  // The slab is whole again for the next cell.
  EXPECT_NE(r->uploadToSlab(slab, prep.meshes[0]).id, 0u) << r->lastError();
}

// A driver that runs out of memory while a slab is carved (its GetError, put in
// the renderer's table, reports GL_OUT_OF_MEMORY once): createSlab says so and
// keeps nothing of that slab; the next one is whole.
GLenum g_injected = GL_NO_ERROR;
PFNGLGETERRORPROC g_real_get_error = nullptr;
GLenum GL_APIENTRY injectedGetError() {
  const GLenum e = g_injected;
  g_injected = GL_NO_ERROR;
  return e != GL_NO_ERROR ? e : g_real_get_error();
}

TEST(SlabCreate, ADriverErrorAtCreateOrAfterAFrameIsReported) {
  Rig rig;
  ASSERT_NE(rig.renderer, nullptr) << rig.why;
  Renderer* r = rig.renderer.get();
  const Scene scene;
  const Prepared prep(scene);
  g_real_get_error = r->api().GetError;
  r->api().GetError = injectedGetError;
  g_injected = GL_OUT_OF_MEMORY;
  EXPECT_EQ(r->createSlab(slabFor(prep)).id, 0u);
  EXPECT_TRUE(r->outOfMemory());
  EXPECT_NE(r->lastError().find("GL out of memory allocating a cell slab"), std::string::npos) << r->lastError();
  const SlabHandle slab = r->createSlab(slabFor(prep));
  EXPECT_EQ(slab.id, 1u);  // the failed slab's place was given back
  EXPECT_FALSE(r->outOfMemory());
  EXPECT_NE(r->uploadToSlab(slab, prep.meshes[0]).id, 0u) << r->lastError();
  g_injected = GL_INVALID_OPERATION;
  EXPECT_EQ(r->createSlab(slabFor(prep)).id, 0u);
  EXPECT_FALSE(r->outOfMemory());
  EXPECT_NE(r->lastError().find("GL error allocating a cell slab"), std::string::npos) << r->lastError();
  // Mid-drive: a frame after which the driver reports an error fails, saying
  // which (blvd_render returns it); the next frame is drawn as before.
  const std::vector<MeshHandle> list{r->uploadToSlab(slab, prep.meshes[1])};
  const std::vector<uint8_t> before = draw(*r, list);
  const Camera cam = viewCamera();
  g_injected = GL_OUT_OF_MEMORY;
  EXPECT_FALSE(r->render(cam, list.data(), list.size(), nullptr));
  EXPECT_NE(r->lastError().find("GL error 0x0505 in render"), std::string::npos) << r->lastError();
  EXPECT_TRUE(draw(*r, list) == before);
  r->api().GetError = g_real_get_error;
}

// A GPU reset (GetError reports GL_CONTEXT_LOST after a frame): that frame
// fails saying so, and so does every later call, at once, without GL: the
// objects are gone and only a new renderer draws again.
TEST(SlabCreate, ALostContextFailsEveryLaterCall) {
  Rig rig;
  ASSERT_NE(rig.renderer, nullptr) << rig.why;
  Renderer* r = rig.renderer.get();
  const Scene scene;
  const Prepared prep(scene);
  const SlabHandle slab = r->createSlab(slabFor(prep));
  ASSERT_NE(slab.id, 0u) << r->lastError();
  const std::vector<MeshHandle> list{r->uploadToSlab(slab, prep.meshes[1])};
  g_real_get_error = r->api().GetError;
  r->api().GetError = injectedGetError;
  g_injected = 0x0507;  // GL_CONTEXT_LOST
  const Camera cam = viewCamera();
  EXPECT_FALSE(r->render(cam, list.data(), list.size(), nullptr));
  EXPECT_TRUE(r->contextLost());
  EXPECT_NE(r->lastError().find("GL context lost"), std::string::npos) << r->lastError();
  r->api().GetError = g_real_get_error;
  EXPECT_FALSE(r->render(cam, list.data(), list.size(), nullptr));
  EXPECT_NE(r->lastError().find("destroy the runtime and create it again"), std::string::npos) << r->lastError();
  EXPECT_EQ(r->uploadToSlab(slab, prep.meshes[0]).id, 0u);
  EXPECT_EQ(r->createSlab(slabFor(prep)).id, 0u);
  std::vector<uint8_t> px(size_t(cam.width) * size_t(cam.height) * 4);
  EXPECT_FALSE(r->readPixels(px.data()));
  EXPECT_NE(r->lastError().find("GL context lost"), std::string::npos) << r->lastError();
}

// Copies the untextured mesh `from` into `slab` in steps of max_bytes.
MeshHandle copyInSteps(Renderer& r, SlabHandle slab, MeshHandle from, uint64_t max_bytes, int& steps) {
  SlabUpload up;
  if (!r.beginSlabCopy(slab, from, up)) return {};
  return finishInSteps(r, up, max_bytes, steps);
}

TEST(SlabCopy, AMeshCopiedBetweenSlabsDrawsWhatTheOriginalDraws) {
  Rig rig;
  ASSERT_NE(rig.renderer, nullptr) << rig.why;
  Renderer* r = rig.renderer.get();
  const Scene scene;
  const Prepared prep(scene);
  const SlabHandle a = r->createSlab(slabFor(prep)), b = r->createSlab(slabFor(prep));
  // The wall first, so that the boxes' offsets differ between the two slabs.
  const MeshHandle wall = r->uploadToSlab(a, prep.meshes[1]);
  const MeshHandle boxes = r->uploadToSlab(a, prep.meshes[0]);
  ASSERT_NE(boxes.id, 0u) << r->lastError();
  const std::vector<uint8_t> original = draw(*r, {boxes});
  int grey = 0;
  for (size_t i = 0; i < original.size(); i += 4) grey += original[i] >= 100 && original[i] <= 200 && original[i + 2] > original[i];
  ASSERT_GT(grey, 100) << "the boxes are not in view";

  int steps = 0;
  const MeshHandle copy = copyInSteps(*r, b, boxes, 1, steps);
  ASSERT_NE(copy.id, 0u) << r->lastError();
  EXPECT_GE(uint64_t(steps), (prep.meshes[0].vertexBytes() + prep.meshes[0].indexBytes()) / 4096);
  EXPECT_EQ(r->slabUsage(b).vertex_bytes, prep.meshes[0].vertexBytes());
  EXPECT_EQ(r->slabUsage(b).index_bytes, prep.meshes[0].indexBytes());
  // The copy stands alone: the source's slab may go.
  r->resetSlab(a);
  EXPECT_EQ(draw(*r, {copy}), original) << "the copied mesh draws differently";

  // A textured mesh is uploaded, not copied (blocks have no texture).
  const MeshHandle wall2 = r->uploadToSlab(a, prep.meshes[1]);
  ASSERT_NE(wall2.id, 0u) << r->lastError();
  SlabUpload up;
  EXPECT_FALSE(r->beginSlabCopy(b, wall2, up));
  EXPECT_NE(r->lastError().find("texture"), std::string::npos) << r->lastError();
  EXPECT_FALSE(r->beginSlabCopy(b, wall, up));  // released with its slab
  EXPECT_FALSE(r->beginSlabCopy(SlabHandle{99}, boxes, up));
}

TEST(SlabCopy, AResetOfTheSourceAbandonsAnUnfinishedCopy) {
  Rig rig;
  ASSERT_NE(rig.renderer, nullptr) << rig.why;
  Renderer* r = rig.renderer.get();
  const Scene scene;
  const Prepared prep(scene);
  const SlabHandle a = r->createSlab(slabFor(prep)), b = r->createSlab(slabFor(prep));
  const MeshHandle boxes = r->uploadToSlab(a, prep.meshes[0]);
  ASSERT_NE(boxes.id, 0u) << r->lastError();
  SlabUpload up;
  ASSERT_TRUE(r->beginSlabCopy(b, boxes, up)) << r->lastError();
  bool finished = true;
  EXPECT_EQ(r->continueSlabUpload(up, 1, finished).id, 0u);
  EXPECT_FALSE(finished);
  // The same mesh placed again at the same offsets is still another mesh.
  r->resetSlab(a);
  ASSERT_NE(r->uploadToSlab(a, prep.meshes[0]).id, 0u);
  EXPECT_EQ(r->continueSlabUpload(up, 1 << 20, finished).id, 0u);
  EXPECT_TRUE(finished);
  EXPECT_NE(r->lastError().find("source mesh is gone"), std::string::npos) << r->lastError();
}


// Packing: every image on the grid, inside the width, clear of the others,
// within NFDH's height bound; the same sizes give the same places.
TEST(SlabAtlas, ImagesArePackedApartWithinTheBound) {
  uint32_t seed = 7;
  auto next = [&seed](int n) { return int((seed = seed * 1664525u + 1013904223u) >> 8) % n; };
  for (int trial = 0; trial < 200; ++trial) {
    const uint32_t n = 1 + uint32_t(next(40));
    std::vector<int> w(n), h(n), x(n), y(n), x2(n), y2(n);
    std::vector<uint32_t> order(n);
    uint64_t area = 0;
    int tallest = 0, widest = 0;
    for (uint32_t i = 0; i < n; ++i) {
      w[i] = 1 + next(600), h[i] = 1 + next(trial % 2 ? 40 : 400);
      area += uint64_t(atlasRound(w[i])) * uint64_t(atlasRound(h[i]));
      tallest = std::max(tallest, h[i]), widest = std::max(widest, w[i]);
    }
    const int width = atlasWidth(widest, area);
    const int height = packSlabAtlas(w.data(), h.data(), n, width, x.data(), y.data(), order.data());
    ASSERT_GT(height, 0);
    EXPECT_EQ(height % kAtlasAlign, 0);
    EXPECT_LE(height, atlasHeightBound(area, tallest, width));
    for (uint32_t i = 0; i < n; ++i) {
      EXPECT_EQ(x[i] % kAtlasAlign, 0);
      EXPECT_EQ(y[i] % kAtlasAlign, 0);
      EXPECT_LE(x[i] + w[i], width);
      EXPECT_LE(y[i] + h[i], height);
      for (uint32_t j = 0; j < i; ++j)
        EXPECT_FALSE(x[i] < x[j] + atlasRound(w[j]) && x[j] < x[i] + atlasRound(w[i]) && y[i] < y[j] + atlasRound(h[j]) &&
                     y[j] < y[i] + atlasRound(h[i]))
            << "images " << i << " and " << j << " overlap";
    }
    EXPECT_EQ(packSlabAtlas(w.data(), h.data(), n, width, x2.data(), y2.data(), order.data()), height);
    EXPECT_EQ(x, x2);
    EXPECT_EQ(y, y2);
  }
  const int w[2] = {100, 40}, h[2] = {10, 0};
  int x[2], y[2];
  uint32_t order[2];
  EXPECT_EQ(packSlabAtlas(w, h, 2, 96, x, y, order), -1);  // wider than the atlas
  EXPECT_EQ(packSlabAtlas(w, h, 2, 160, x, y, order), 16);  // the image without texels takes no place
}

// The magenta neighbour of the atlas tests, 150 x 130.
geo::MeshData magentaWall() {
  return farWall(150, 130, [](int, int, uint8_t* t) { t[0] = 255, t[1] = 0, t[2] = 255, t[3] = 255; });
}

// As the bake's layer images are: the mesh maps all but a gutter of 4 texels
// (kAtlasGutter) round its tw x th image.
void mapInsideGutter(geo::MeshData& wall, int tw, int th) {
  const float u0 = 4.f / float(tw), u1 = 1 - u0, v0 = 4.f / float(th), v1 = 1 - v0;
  wall.texcoords = {u0, v0, u1, v0, u1, v1, u0, v1};
}

// A slab for `meshes` meshes the size of `like` whose atlas, `width` wide on
// `format`'s grid, holds the magenta image and a 203 x 117 wall: packed
// (packSlabAtlas), their places written into `pink` and `wall`.
SlabDesc twoImageSlab(const PreparedMesh& like, uint32_t meshes, int width, AtlasFormat format, PreparedMesh& pink,
                      PreparedMesh& wall) {
  const int w[2] = {150, 203}, h[2] = {130, 117};
  int x[2], y[2];
  uint32_t order[2];
  SlabDesc d;
  d.vertex_bytes = meshes * like.vertexBytes();
  d.index_bytes = meshes * (like.indexBytes() + 4);
  d.meshes = meshes;
  d.atlas_width = width;
  d.atlas_format = format;
  d.atlas_height = packSlabAtlas(w, h, 2, d.atlas_width, x, y, order, atlasAlign(format));
  pink.atlas_x = x[0], pink.atlas_y = y[0];
  wall.atlas_x = x[1], wall.atlas_y = y[1];
  return d;
}

// Two images in one atlas, the second beside a magenta one: each draws as it
// does alone in an atlas of the same size, and the neighbour never bleeds in,
// from the finest level to the coarsest the atlas has.
TEST(SlabAtlas, AnImageDrawsTheSameBesideAnother) {
  Rig rig;
  ASSERT_NE(rig.renderer, nullptr) << rig.why;
  Renderer* r = rig.renderer.get();
  const geo::MeshData pink = magentaWall();
  geo::MeshData wall = farWall(203, 117, [](int x, int y, uint8_t* t) {
    t[0] = uint8_t(40 + (x * 7) % 60), t[1] = uint8_t(60 + (y * 5) % 80), t[2] = 70, t[3] = 255;
  });
  mapInsideGutter(wall, 203, 117);
  std::vector<uint8_t> block(preparedBytes(4, 6, 150, 130) + 2 * preparedBytes(4, 6, 203, 117));
  StagingArena arena{block.data(), block.size(), 0};
  PreparedMesh pp, alone, beside;
  std::string err;
  ASSERT_TRUE(prepareMesh(pink, arena, pp, err)) << err;
  ASSERT_TRUE(prepareMesh(wall, arena, alone, err)) << err;
  ASSERT_TRUE(prepareMesh(wall, arena, beside, err)) << err;
  const SlabDesc d = twoImageSlab(pp, 2, 360, AtlasFormat::Rgba8, pp, beside);
  ASSERT_EQ(d.atlas_height, 136);
  ASSERT_EQ(beside.atlas_x, 152);  // right after the (taller) pink image's place
  alone.atlas_x = alone.atlas_y = 0;
  const SlabHandle one = r->createSlab(d), two = r->createSlab(d);
  const MeshHandle a = r->uploadToSlab(one, alone);
  ASSERT_NE(r->uploadToSlab(two, pp).id, 0u) << r->lastError();
  const MeshHandle b = r->uploadToSlab(two, beside);
  ASSERT_NE(a.id, 0u) << r->lastError();
  ASSERT_NE(b.id, 0u) << r->lastError();
  EXPECT_EQ(r->slabUsage(two).textures, 2u);
  EXPECT_EQ(r->slabUsage(two).texture_bytes, atlasBytes(152, 136) + atlasBytes(208, 120));
  for (double back : {0.0, -300.0, -700.0}) {  // 260 to 960 m: finer to coarser than the atlas's last level
    const std::vector<uint8_t> empty = draw(*r, {}, back), fa = draw(*r, {a}, back), fb = draw(*r, {b}, back);
    int wall_px = 0, magenta = 0, worst = 0;
    for (size_t i = 0; i < fb.size(); i += 4) {
      wall_px += std::memcmp(&fa[i], &empty[i], 3) != 0;
      magenta += fb[i] > 150 && fb[i + 1] < 100 && fb[i + 2] > 150;
      for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(int(fa[i + k]) - int(fb[i + k])));
    }
    EXPECT_GT(wall_px, 0) << "the wall is not in the frame " << back << " m back";
    EXPECT_EQ(magenta, 0) << back << " m back";
    EXPECT_LE(worst, 2) << back << " m back";
  }
}

// A place off the grid, outside the atlas or over another image is refused,
// and nothing of the refused mesh stays in the slab.
TEST(SlabAtlas, ABadPlaceIsRefused) {
  Rig rig;
  ASSERT_NE(rig.renderer, nullptr) << rig.why;
  Renderer* r = rig.renderer.get();
  const Scene scene;
  Prepared prep(scene);
  const SlabHandle slab = r->createSlab(slabFor(prep));
  PreparedMesh m = prep.meshes[1];  // 256 x 128
  ASSERT_NE(r->uploadToSlab(slab, m).id, 0u) << r->lastError();
  m.atlas_x = 4;
  EXPECT_EQ(r->uploadToSlab(slab, m).id, 0u);
  EXPECT_NE(r->lastError().find("grid"), std::string::npos) << r->lastError();
  m.atlas_x = 240;
  EXPECT_EQ(r->uploadToSlab(slab, m).id, 0u);
  EXPECT_NE(r->lastError().find("overlaps"), std::string::npos) << r->lastError();
  m.atlas_x = 256, m.atlas_y = 144;
  EXPECT_EQ(r->uploadToSlab(slab, m).id, 0u);
  EXPECT_NE(r->lastError().find("outside the atlas"), std::string::npos) << r->lastError();
  m.atlas_x = -1;
  EXPECT_EQ(r->uploadToSlab(slab, m).id, 0u);
  EXPECT_EQ(r->slabUsage(slab).textures, 1u);
  EXPECT_EQ(r->slabUsage(slab).meshes, 1u);
  m.atlas_x = 256, m.atlas_y = 128;
  EXPECT_NE(r->uploadToSlab(slab, m).id, 0u) << r->lastError();
  EXPECT_EQ(r->slabUsage(slab).textures, 2u);
}

// An ETC2 atlas (places on a 32-texel grid, each level's blocks encoded on
// the preparing thread) draws the wall within the codec's error of the RGBA8
// atlas, uploaded in small steps as whole; a magenta neighbour never bleeds
// in; the slot holds an eighth of the texel bytes.
TEST(SlabAtlas, AnEtc2AtlasDrawsAsTheRgba8OneWithinTheCodecsError) {
  Rig rig;
  ASSERT_NE(rig.renderer, nullptr) << rig.why;
  Renderer* r = rig.renderer.get();
  ASSERT_TRUE(r->supportsEtc2()) << "GL " << r->glVersion() << " has no ETC2";
  const geo::MeshData pink = magentaWall();
  geo::MeshData wall = farWall(203, 117, [](int x, int y, uint8_t* t) {
    t[0] = uint8_t(60 + 2 * x % 90), t[1] = uint8_t(60 + y), t[2] = 70, t[3] = 255;
  });
  mapInsideGutter(wall, 203, 117);
  std::vector<uint8_t> block(2 * (preparedBytes(4, 6, 150, 130) + atlasEtc2Bytes(150, 130)) +
                             3 * (preparedBytes(4, 6, 203, 117) + atlasEtc2Bytes(203, 117)));
  StagingArena arena{block.data(), block.size(), 0};
  PreparedMesh pp, plain, packed;
  std::string err;
  ASSERT_TRUE(prepareMesh(pink, arena, pp, err)) << err;
  ASSERT_TRUE(prepareMesh(wall, arena, plain, err)) << err;
  ASSERT_TRUE(prepareMesh(wall, arena, packed, err)) << err;
  ASSERT_TRUE(encodeAtlasEtc2(pp, arena, err)) << err;
  ASSERT_TRUE(encodeAtlasEtc2(packed, arena, err)) << err;
  const SlabDesc d = twoImageSlab(pp, 3, 384, AtlasFormat::Etc2, pp, packed);
  ASSERT_EQ(d.atlas_height, 160);
  ASSERT_EQ(packed.atlas_x, 160);  // right after the (taller) pink image's place
  SlabDesc rgba = d;
  rgba.atlas_format = AtlasFormat::Rgba8;
  plain.atlas_x = plain.atlas_y = 0;
  EXPECT_EQ(slabGpuBytes(d) - d.vertex_bytes - d.index_bytes,
            (slabGpuBytes(rgba) - rgba.vertex_bytes - rgba.index_bytes) / 8);
  const SlabHandle one = r->createSlab(rgba), two = r->createSlab(d);
  ASSERT_NE(two.id, 0u) << r->lastError();
  const MeshHandle a = r->uploadToSlab(one, plain);
  ASSERT_NE(r->uploadToSlab(two, pp).id, 0u) << r->lastError();
  SlabUpload up;
  ASSERT_TRUE(r->beginSlabUpload(two, packed, up)) << r->lastError();
  int steps = 0;
  const MeshHandle b = finishInSteps(*r, up, 512, steps);  // at least 4096 bytes a step
  ASSERT_NE(a.id, 0u) << r->lastError();
  ASSERT_NE(b.id, 0u) << r->lastError();
  EXPECT_GE(steps, int(atlasEtc2Bytes(203, 117) / 4096));
  EXPECT_EQ(r->slabUsage(two).texture_bytes,
            atlasBytes(160, 160, AtlasFormat::Etc2) + atlasBytes(224, 128, AtlasFormat::Etc2));
  // An image without its ETC2 levels has no place in an ETC2 atlas.
  PreparedMesh bare = plain;
  bare.atlas_x = 0, bare.atlas_y = 160 - 32;
  EXPECT_EQ(r->uploadToSlab(two, bare).id, 0u);
  EXPECT_NE(r->lastError().find("ETC2"), std::string::npos) << r->lastError();
  for (double back : {0.0, -300.0, -700.0}) {
    const std::vector<uint8_t> empty = draw(*r, {}, back), fa = draw(*r, {a}, back), fb = draw(*r, {b}, back);
    int wall_px = 0, magenta = 0;
    double se = 0;
    for (size_t i = 0; i < fb.size(); i += 4) {
      if (std::memcmp(&fa[i], &empty[i], 3) == 0) continue;
      ++wall_px;
      magenta += fb[i] > 150 && fb[i + 1] < 100 && fb[i + 2] > 150;
      for (int k = 0; k < 3; ++k) se += (double(fa[i + k]) - fb[i + k]) * (double(fa[i + k]) - fb[i + k]);
    }
    ASSERT_GT(wall_px, 0) << "the wall is not in the frame " << back << " m back";
    EXPECT_EQ(magenta, 0) << back << " m back";
    const double psnr = 10 * std::log10(255.0 * 255.0 / std::max(1e-9, se / (3.0 * wall_px)));
    EXPECT_GE(psnr, 30.0) << back << " m back";
  }
}

}  // namespace
}  // namespace blvd::render
