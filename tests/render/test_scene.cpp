// Rendering on every backend: a red box in front of the camera under the
// sky, checked pixel by pixel and against a golden image; a small city for
// culling statistics and for a human to look at; mesh handle lifetimes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <set>

#include "render/context.h"
#include "imaging/image.h"
#include "render/renderer.h"
#include "scene.h"

namespace blvd::render {
namespace {

using test::Rgb;
using imaging::psnr;
using imaging::readPng;
using imaging::writePng;

constexpr int kW = 160, kH = 120;
constexpr uint8_t kRed[4] = {200, 40, 40, 255};

struct Rig {
  std::unique_ptr<Context> ctx;
  std::unique_ptr<Renderer> renderer;
};

// Context + renderer for `b`; on failure `why` says which and why.
Rig makeRig(Backend b, int w, int h, std::string& why, uint32_t capacity = 0) {
  Rig rig;
  rig.ctx = createContext(b, why);
  if (!rig.ctx) return rig;
  RendererDesc desc;
  desc.width = w;
  desc.height = h;
  desc.mesh_capacity = capacity;
  rig.renderer = Renderer::create(*rig.ctx, desc, why);
  return rig;
}

Camera boxCamera() {
  Camera cam;
  cam.eye_enu = {0.0, 0.0, 2.0};  // 2 m up, looking north
  cam.width = kW;
  cam.height = kH;
  return cam;
}

// A renderer of kW x kH on the backend of the parameter (egl-device is
// skipped where there is none).
class BackendScene : public ::testing::TestWithParam<Backend> {
 protected:
  void SetUp() override {
    rig = makeRig(GetParam(), kW, kH, why);
    if (GetParam() == Backend::EglDevice && !rig.ctx) {
      GTEST_SKIP() << "egl-device unavailable here: " << why;
    }
    ASSERT_NE(rig.renderer, nullptr) << why;
  }
  std::string why;
  Rig rig;
};

TEST_P(BackendScene, BoxInFrontOfTheCamera) {
  Renderer& r = *rig.renderer;

  // 4 m cube whose near face is 8 m north of the eye (glTF z = -north).
  const MeshHandle box = r.upload(test::makeBox(0, 2, -10, 4, 4, 4, kRed));
  ASSERT_TRUE(r.isValid(box)) << r.lastError();
  FrameStats stats;
  ASSERT_TRUE(r.render(boxCamera(), &box, 1, &stats)) << r.lastError();
  EXPECT_EQ(stats.draw_calls, 2u);  // background + box
  EXPECT_EQ(stats.triangles, 12u);
  EXPECT_EQ(stats.meshes_drawn, 1u);
  EXPECT_EQ(stats.meshes_culled, 0u);
  EXPECT_GT(stats.frame_ms, 0.0);

  std::vector<uint8_t> img(static_cast<size_t>(kW) * kH * 4);
  ASSERT_TRUE(r.readPixels(img.data())) << r.lastError();
  std::string err;
  const std::string name = std::string("box_") + backendName(GetParam()) + ".png";
  ASSERT_TRUE(writePng(test::outPath(name), kW, kH, img.data(), err)) << err;

  // Top row: sky, bluer than it is red, brighter towards the top than at
  // the horizon... and the same all along the row (no geometry there).
  const Rgb top = test::pixel(img, kW, kW / 2, 0);
  EXPECT_GT(top.b, top.r + 30) << top.r << "," << top.g << "," << top.b;
  EXPECT_GT(top.b, top.g);
  const Rgb top_left = test::pixel(img, kW, 0, 0);
  EXPECT_NEAR(top_left.b, top.b, 6);

  // Centre: the box's south face, sunlit from the south-south-west.
  const Rgb mid = test::pixel(img, kW, kW / 2, kH / 2);
  EXPECT_GT(mid.r, 150) << mid.r << "," << mid.g << "," << mid.b;
  EXPECT_LT(mid.g, 90);
  EXPECT_LT(mid.b, 90);

  // Bottom corner: the ground, grey-green (green above blue, unlike the sky).
  const Rgb ground = test::pixel(img, kW, 2, kH - 1);
  EXPECT_GT(ground.g, ground.b) << ground.r << "," << ground.g << "," << ground.b;
  EXPECT_LT(std::abs(ground.r - ground.g), 40);

  // Not blank: many distinct colours (gradient sky, fogged ground, box).
  std::set<uint32_t> colours;
  for (size_t i = 0; i < img.size(); i += 4) {
    colours.insert(uint32_t{img[i]} << 16 | uint32_t{img[i + 1]} << 8 | img[i + 2]);
  }
  EXPECT_GT(colours.size(), 20u);

  // Golden image, shared by all backends: GLES on EGL and desktop GL on
  // OSMesa must agree. BLVD_UPDATE_GOLDEN=1 rewrites it.
  const std::string golden = std::string(BLVD_RENDER_GOLDEN_DIR) + "/box.png";
  if (std::getenv("BLVD_UPDATE_GOLDEN")) {
    ASSERT_TRUE(writePng(golden, kW, kH, img.data(), err)) << err;
  }
  int gw = 0, gh = 0;
  std::vector<uint8_t> gold;
  ASSERT_TRUE(readPng(golden, gw, gh, gold, err)) << err;
  ASSERT_EQ(gw, kW);
  ASSERT_EQ(gh, kH);
  const double db = psnr(img.data(), gold.data(), static_cast<size_t>(kW) * kH);
  std::printf("%s: PSNR vs golden %.1f dB, frame %.2f ms\n", backendName(GetParam()), db,
              stats.frame_ms);
  EXPECT_GT(db, 35.0) << "compare " << test::outPath(name) << " with " << golden;
}

// Meshes drawn behind (the terrain) show only where the others drew
// nothing, however near they are, and still hide one another.
// On every backend: GLES has glDepthRangef, desktop GL 3.3 glDepthRange.
TEST_P(BackendScene, MeshesDrawnBehindShowOnlyWhereNothingElseDrew) {
  Renderer& r = *rig.renderer;
  const uint8_t green[4] = {40, 200, 40, 255}, blue[4] = {40, 40, 220, 255};
  // The red box 8 m ahead; a wide green wall 5 m ahead, in front of it; a
  // blue wall 6 m ahead behind the green one, wider still.
  const MeshHandle list[3] = {r.upload(test::makeBox(0, 2, -10, 4, 4, 4, kRed)),
                              r.upload(test::makeBox(0, 2, -5.5f, 6, 1.4f, 1, green)),
                              r.upload(test::makeBox(0, 2, -6.5f, 8, 3, 1, blue))};
  for (const MeshHandle& h : list) ASSERT_TRUE(r.isValid(h)) << r.lastError();
  std::vector<uint8_t> img(static_cast<size_t>(kW) * kH * 4);
  auto at = [&](int x, int y) { return test::pixel(img, kW, x, y); };
  auto isRed = [](Rgb c) { return c.r > 150 && c.g < 90 && c.b < 90; };
  auto isGreen = [](Rgb c) { return c.g > 120 && c.r < 90 && c.b < 90; };
  auto isBlue = [](Rgb c) { return c.b > 120 && c.r < 90 && c.g < 90; };

  // Drawn as one: the green wall hides the box's middle.
  ASSERT_TRUE(r.render(boxCamera(), list, 3, nullptr)) << r.lastError();
  ASSERT_TRUE(r.readPixels(img.data())) << r.lastError();
  EXPECT_TRUE(isGreen(at(kW / 2, kH / 2)));

  // The walls behind the box: the box shows whole; beside it the walls, the
  // green one in front of the blue one; above the green wall the blue one.
  RenderOptions opt;
  opt.behind_from = 1;
  ASSERT_TRUE(r.render(boxCamera(), list, 3, nullptr, opt)) << r.lastError();
  ASSERT_TRUE(r.readPixels(img.data())) << r.lastError();
  EXPECT_TRUE(isRed(at(kW / 2, kH / 2)));
  int green_px = 0, blue_px = 0, red_px = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) green_px += isGreen(at(x, y)), blue_px += isBlue(at(x, y)), red_px += isRed(at(x, y));
  EXPECT_GT(green_px, 200);
  EXPECT_GT(blue_px, 200);
  EXPECT_GT(red_px, 1000);
  // The green wall's row beside the box is green, not blue.
  const int row = kH / 2;
  for (int x = 0; x < kW; ++x) {
    const Rgb c = at(x, row);
    if (!isRed(c)) {
      EXPECT_TRUE(isGreen(c)) << "column " << x << ": " << c.r << "," << c.g << "," << c.b;
    }
  }
  for (const MeshHandle& h : list) r.release(h);
}

// A line mesh: one segment east-west, x in [-half, half], `z` metres ahead
// (glTF z = -north), at height y.
geo::MeshData lineAcross(float z, float y, float half) {
  geo::MeshData m;
  m.positions = {-half, y, z, half, y, z};
  m.indices = {0, 1};
  return m;
}

// The ids (RGB, 0 = nothing) of an item-buffer read-back.
std::vector<uint32_t> idsOf(const std::vector<uint8_t>& img) {
  std::vector<uint32_t> ids(img.size() / 4);
  for (size_t i = 0; i < ids.size(); ++i)
    ids[i] = img[i * 4 + 3] ? uint32_t(img[i * 4]) | uint32_t(img[i * 4 + 1]) << 8 | uint32_t(img[i * 4 + 2]) << 16 : 0;
  return ids;
}

// Lines drawn over the depth an item buffer left (keep_depth) mark the
// pixels they cross where no surface hides them: the bake's conservative
// item buffer. GL_LINES on GLES (EGL) and on desktop GL (OSMesa) alike.
TEST_P(BackendScene, LinesOverTheKeptDepthShowOnlyWhereNothingHidesThem) {
  Renderer& r = *rig.renderer;
  const MeshHandle box = r.upload(test::makeBox(0, 2, -10, 4, 4, 4, kRed));
  const MeshHandle behind = r.uploadLines(lineAcross(-30.0f, 1.0f, 40.0f));
  const MeshHandle before = r.uploadLines(lineAcross(-5.0f, 1.9f, 1.0f));  // before the box's face
  ASSERT_TRUE(r.isValid(box) && r.isValid(behind) && r.isValid(before)) << r.lastError();
  RenderOptions opt;
  opt.pass = Pass::ItemBuffer;
  const uint32_t box_id = 1, line_ids[2] = {2, 3};
  opt.item_ids = &box_id;
  std::vector<uint8_t> img(static_cast<size_t>(kW) * kH * 4);
  ASSERT_TRUE(r.render(boxCamera(), &box, 1, nullptr, opt)) << r.lastError();
  ASSERT_TRUE(r.readPixels(img.data())) << r.lastError();
  const std::vector<uint32_t> boxes = idsOf(img);
  FrameStats stats;
  opt.keep_depth = true;
  opt.item_ids = line_ids;
  const MeshHandle lines[2] = {behind, before};
  ASSERT_TRUE(r.render(boxCamera(), lines, 2, &stats, opt)) << r.lastError();
  EXPECT_EQ(stats.triangles, 0u);  // lines are not triangles
  ASSERT_TRUE(r.readPixels(img.data())) << r.lastError();
  const std::vector<uint32_t> ids = idsOf(img);
  int behind_px = 0, before_px = 0, box_px = 0;
  for (size_t i = 0; i < ids.size(); ++i) {
    box_px += boxes[i] == 1;
    EXPECT_NE(ids[i], 1u) << "the colour was not cleared at pixel " << i;
    if (ids[i] == 2) {
      ++behind_px;
      EXPECT_EQ(boxes[i], 0u) << "the line behind the box shows through it at pixel " << i;
    }
    if (ids[i] == 3) {
      ++before_px;
      EXPECT_EQ(boxes[i], 1u) << "pixel " << i;  // it crosses the box's face only
    }
  }
  EXPECT_GT(box_px, 1000);
  EXPECT_GT(behind_px, kW / 3);   // a pixel a column beside the box
  EXPECT_GT(before_px, 10);       // the near line over the box's face
  // Only an item buffer keeps its depth; a line mesh's indices come in pairs.
  opt.pass = Pass::Shaded;
  EXPECT_FALSE(r.render(boxCamera(), lines, 2, nullptr, opt));
  EXPECT_NE(r.lastError().find("keep_depth"), std::string::npos);
  geo::MeshData odd = lineAcross(-5.0f, 1.0f, 1.0f);
  odd.indices.push_back(1);
  EXPECT_FALSE(r.isValid(r.uploadLines(odd)));
  EXPECT_NE(r.lastError().find("pairs"), std::string::npos);
  for (const MeshHandle& h : {box, behind, before}) r.release(h);
}

INSTANTIATE_TEST_SUITE_P(Render, BackendScene,
                         ::testing::Values(Backend::EglSurfaceless, Backend::EglDevice,
                                           Backend::OSMesa),
                         [](const ::testing::TestParamInfo<Backend>& p) {
                           switch (p.param) {
                             case Backend::EglSurfaceless: return std::string("EglSurfaceless");
                             case Backend::EglDevice: return std::string("EglDevice");
                             case Backend::OSMesa: return std::string("OSMesa");
                             default: return std::string("Other");
                           }
                         });

// A 9 x 9 grid of blocks with streets between them, seen from a street.
struct City {
  std::vector<MeshHandle> meshes;
  size_t boxes = 0;
};

City buildCity(Renderer& r) {
  City city;
  const uint8_t street[4] = {90, 90, 95, 255};
  const uint8_t palette[4][4] = {
      {200, 180, 150, 255}, {170, 120, 100, 255}, {210, 210, 200, 255}, {140, 150, 170, 255}};
  for (int i = -4; i <= 4; ++i) {
    for (int j = -4; j <= 4; ++j) {
      // 40 m blocks on a 60 m pitch: 20 m streets along x = 30 + 60k.
      const float cx = static_cast<float>(i * 60), cz = static_cast<float>(j * 60);
      const float h = 8.0f + static_cast<float>((i * 7 + j * 13 + 100) % 5) * 6.0f;
      city.meshes.push_back(
          r.upload(test::makeBox(cx, h / 2, cz, 40, h, 40, palette[(i + j + 8) % 4])));
      ++city.boxes;
    }
    // Street ribbons 5 cm above the ground plane, one per row and column.
    const float s = static_cast<float>(i * 60 + 30);
    city.meshes.push_back(r.upload(test::makeFlat(s - 8, -270, s + 8, 270, 0.05f, street)));
    city.meshes.push_back(r.upload(test::makeFlat(-270, s - 8, 270, s + 8, 0.05f, street)));
  }
  return city;
}

TEST(Render, CityCullsAndLooksRight) {
  std::string why;
  Rig rig = makeRig(Backend::Auto, 800, 480, why);
  ASSERT_NE(rig.renderer, nullptr) << why;
  Renderer& r = *rig.renderer;
  City city = buildCity(r);
  for (MeshHandle h : city.meshes) ASSERT_TRUE(r.isValid(h)) << r.lastError();

  // On the street x = 30, 1.5 m up, looking north-north-east, slightly down.
  Camera cam;
  cam.eye_enu = {30.0, -200.0, 1.5};
  cam.heading_deg = 10.0;
  cam.pitch_deg = -2.0;
  FrameStats stats;
  ASSERT_TRUE(r.render(cam, city.meshes.data(), city.meshes.size(), &stats)) << r.lastError();
  std::vector<uint8_t> img(800u * 480u * 4u);
  ASSERT_TRUE(r.readPixels(img.data()));
  std::string err;
  ASSERT_TRUE(writePng(test::outPath("city_" + std::string(r.backendName()) + ".png"), 800, 480,
                       img.data(), err))
      << err;
  std::printf("%s city: %u drawn, %u culled, %llu triangles, %u draw calls, %.2f ms\n",
              r.backendName(), stats.meshes_drawn, stats.meshes_culled,
              static_cast<unsigned long long>(stats.triangles), stats.draw_calls, stats.frame_ms);
  EXPECT_EQ(stats.meshes_drawn + stats.meshes_culled, city.meshes.size());
  EXPECT_GT(stats.meshes_culled, 20u);  // everything south of the eye, and the flanks
  EXPECT_EQ(stats.draw_calls, stats.meshes_drawn + 1);

  // Turning around swaps what is culled.
  cam.heading_deg = 190.0;
  FrameStats back;
  ASSERT_TRUE(r.render(cam, city.meshes.data(), city.meshes.size(), &back));
  EXPECT_LT(back.meshes_drawn, stats.meshes_drawn);

  // From above the south-west corner: fog, ground plane and horizon.
  Camera overview;
  overview.eye_enu = {-330.0, -330.0, 60.0};
  overview.heading_deg = 45.0;
  overview.pitch_deg = -12.0;
  FrameStats over;
  ASSERT_TRUE(r.render(overview, city.meshes.data(), city.meshes.size(), &over));
  ASSERT_TRUE(r.readPixels(img.data()));
  ASSERT_TRUE(writePng(test::outPath("city_overview_" + std::string(r.backendName()) + ".png"),
                       800, 480, img.data(), err))
      << err;
  EXPECT_GT(over.meshes_drawn, stats.meshes_drawn);

  // The street ribbon right below the camera must win against the ground
  // plane: a bottom-centre pixel looking north is street grey, not green.
  cam.heading_deg = 0.0;
  cam.pitch_deg = -30.0;
  ASSERT_TRUE(r.render(cam, city.meshes.data(), city.meshes.size(), nullptr));
  ASSERT_TRUE(r.readPixels(img.data()));
  const Rgb below = test::pixel(img, 800, 400, 470);
  EXPECT_LE(std::abs(below.g - below.b), 8) << below.r << "," << below.g << "," << below.b;
}

TEST(Render, HandlesAndPool) {
  std::string why;
  Rig rig = makeRig(Backend::Auto, 64, 48, why, /*capacity=*/2);
  ASSERT_NE(rig.renderer, nullptr) << why;
  Renderer& r = *rig.renderer;
  const geo::MeshData box = test::makeBox(0, 2, -10, 4, 4, 4, kRed);

  const MeshHandle a = r.upload(box);
  const MeshHandle b = r.upload(box);
  ASSERT_TRUE(r.isValid(a));
  ASSERT_TRUE(r.isValid(b));
  EXPECT_EQ(r.meshCount(), 2u);
  EXPECT_EQ(r.meshBytes(), 2u * (24u * 20u + 36u * 2u));  // 20-byte vertices, 16-bit indices
  EXPECT_FALSE(r.isValid(r.upload(box)));                  // pool full
  EXPECT_NE(r.lastError().find("pool full"), std::string::npos) << r.lastError();

  r.release(a);
  EXPECT_FALSE(r.isValid(a));
  r.release(a);  // stale: ignored
  r.release(MeshHandle{});
  const MeshHandle c = r.upload(box);  // reuses a's slot with a new generation
  ASSERT_TRUE(r.isValid(c));
  EXPECT_NE(c, a);
  EXPECT_FALSE(r.isValid(a));

  Camera cam = boxCamera();
  cam.width = 64;
  cam.height = 48;
  const MeshHandle list[] = {a, b, c, MeshHandle{}};
  FrameStats stats;
  ASSERT_TRUE(r.render(cam, list, 4, &stats)) << r.lastError();
  EXPECT_EQ(stats.meshes_invalid, 2u);
  EXPECT_EQ(stats.meshes_drawn, 2u);

  // A viewport larger than the framebuffer is refused, not clipped.
  cam.width = 65;
  EXPECT_FALSE(r.render(cam, list, 4, &stats));
}

TEST(Render, RejectsMalformedMeshes) {
  std::string why;
  Rig rig = makeRig(Backend::Auto, 32, 32, why);
  ASSERT_NE(rig.renderer, nullptr) << why;
  Renderer& r = *rig.renderer;
  geo::MeshData m = test::makeBox(0, 0, 0, 1, 1, 1, kRed);
  m.indices.back() = 24;  // one past the last vertex
  EXPECT_FALSE(r.isValid(r.upload(m)));
  EXPECT_NE(r.lastError().find("out of range"), std::string::npos);
  m = test::makeBox(0, 0, 0, 1, 1, 1, kRed);
  m.normals.pop_back();
  EXPECT_FALSE(r.isValid(r.upload(m)));
  m = test::makeBox(0, 0, 0, 1, 1, 1, kRed);
  m.colors.resize(4);
  EXPECT_FALSE(r.isValid(r.upload(m)));
  EXPECT_FALSE(r.isValid(r.upload(geo::MeshData{})));
  EXPECT_EQ(r.meshCount(), 0u);
  // Bad cameras are refused with a reason.
  Camera cam;
  cam.width = 32;
  cam.height = 32;
  cam.fov_y_deg = 0.0;
  EXPECT_FALSE(r.render(cam, nullptr, 0, nullptr));
  EXPECT_NE(r.lastError().find("fov"), std::string::npos);
  EXPECT_FALSE(r.readPixels(nullptr));
}

TEST(Render, LargeMeshUses32BitIndices) {
  std::string why;
  Rig rig = makeRig(Backend::Auto, 64, 48, why);
  ASSERT_NE(rig.renderer, nullptr) << why;
  Renderer& r = *rig.renderer;
  // 2800 boxes = 67200 vertices, more than 16-bit indices can address.
  geo::MeshData big;
  for (int i = 0; i < 2800; ++i) {
    big.append(test::makeBox(static_cast<float>(i % 70) - 35.0f, 0.5f,
                             -20.0f - static_cast<float>(i / 70), 0.5f, 0.5f, 0.5f, kRed));
  }
  const MeshHandle h = r.upload(big);
  ASSERT_TRUE(r.isValid(h)) << r.lastError();
  EXPECT_EQ(r.meshBytes(), 67200u * 20u + big.indices.size() * 4u);
  Camera cam = boxCamera();
  cam.width = 64;
  cam.height = 48;
  cam.eye_enu.y = -60.0;  // far enough back to see every part (LongMeshDrawsOnlyItsPartsInView culls some)
  FrameStats stats;
  ASSERT_TRUE(r.render(cam, &h, 1, &stats)) << r.lastError();
  EXPECT_EQ(stats.triangles, 2800u * 12u);
  EXPECT_EQ(stats.parts_culled, 0u);
}

// A row of 200 boxes 200 m long as one mesh: four parts of 50 m, and the
// camera 20 m away sees the middle two. Only they are drawn, in one call,
// and the frame is what the same boxes give as 200 meshes of their own.
TEST(Render, LongMeshDrawsOnlyItsPartsInView) {
  std::string why;
  Rig rig = makeRig(Backend::Auto, kW, kH, why, 256);
  ASSERT_NE(rig.renderer, nullptr) << why;
  Renderer& r = *rig.renderer;
  geo::MeshData row;
  std::vector<MeshHandle> each;
  for (int i = 0; i < 200; ++i) {
    const geo::MeshData box = test::makeBox(float(i) - 99.5f, 1.0f, -20.0f, 0.6f, 2.0f, 0.6f, kRed);
    row.append(box);
    each.push_back(r.upload(box));
    ASSERT_TRUE(r.isValid(each.back())) << r.lastError();
  }
  const MeshHandle h = r.upload(row);
  ASSERT_TRUE(r.isValid(h)) << r.lastError();
  const Camera cam = boxCamera();
  FrameStats one;
  ASSERT_TRUE(r.render(cam, &h, 1, &one)) << r.lastError();
  std::vector<uint8_t> a(size_t(kW) * kH * 4), b(a.size());
  ASSERT_TRUE(r.readPixels(a.data()));
  EXPECT_EQ(one.parts_culled, 2u);
  EXPECT_EQ(one.triangles, 100u * 12u);
  EXPECT_EQ(one.draw_calls, 2u);  // the two parts in one call, and the sky
  FrameStats many;
  ASSERT_TRUE(r.render(cam, each.data(), each.size(), &many)) << r.lastError();
  ASSERT_TRUE(r.readPixels(b.data()));
  EXPECT_LT(many.triangles, one.triangles);  // whole boxes culled finer still
  size_t differ = 0, red = 0;
  for (size_t i = 0; i < a.size(); i += 4) {
    differ += std::abs(int(a[i]) - int(b[i])) > 8;
    red += a[i] > a[i + 1] + 60;
  }
  EXPECT_GT(red, size_t(kW));  // the boxes show
  EXPECT_LE(differ, a.size() / 4 / 200);  // edge pixels at most
}

}  // namespace
}  // namespace blvd::render
