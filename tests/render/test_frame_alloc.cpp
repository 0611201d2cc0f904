// After warm-up, render() and readPixels() make no heap allocations through
// operator new (DESIGN: zero allocations per frame on the render thread).
// The driver's own malloc calls are outside blvd's control and not counted.
#include <gtest/gtest.h>

#include <atomic>
#include <memory>
#include <cstdlib>
#include <new>

#include "render/context.h"
#include "render/renderer.h"
#include "scene.h"

// Under AddressSanitizer the sanitizer owns operator new; replacing it again
// makes ASan report new/free mismatches, so the check is skipped there.
#if defined(__SANITIZE_ADDRESS__)
#define BLVD_COUNT_NEW 0
#else
#define BLVD_COUNT_NEW 1
#endif

namespace {
std::atomic<bool> g_counting{false};
std::atomic<size_t> g_allocations{0};
}  // namespace

#if BLVD_COUNT_NEW
// noinline: inlined into callers, GCC would pair the malloc/free inside
// with the new/delete outside and warn (-Wmismatched-new-delete).
__attribute__((noinline)) void* operator new(size_t n) {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
__attribute__((noinline)) void operator delete(void* p) noexcept { std::free(p); }
__attribute__((noinline)) void operator delete(void* p, size_t) noexcept { std::free(p); }
#endif

namespace blvd::render {
namespace {

TEST(FrameAlloc, RenderAndReadPixelsAllocateNothingAfterWarmUp) {
  if (!BLVD_COUNT_NEW) GTEST_SKIP() << "operator new belongs to AddressSanitizer in this build";
  std::string why;
  auto ctx = createContext(Backend::Auto, why);
  ASSERT_NE(ctx, nullptr) << why;
  RendererDesc desc;
  desc.width = 128;
  desc.height = 96;
  auto r = Renderer::create(*ctx, desc, why);
  ASSERT_NE(r, nullptr) << why;
  const uint8_t grey[4] = {150, 150, 150, 255};
  std::vector<MeshHandle> list;
  for (int i = 0; i < 20; ++i) {
    list.push_back(r->upload(test::makeBox(static_cast<float>(i * 6 - 60), 3, -30, 4, 6, 4, grey)));
  }
  list.push_back(MeshHandle{});  // an invalid entry takes the skip path too
  Camera cam;
  cam.width = 128;
  cam.height = 96;
  std::vector<uint8_t> img(128u * 96u * 4u);
  FrameStats stats;
  for (int i = 0; i < 2; ++i) {  // warm-up: the driver compiles its variants
    ASSERT_TRUE(r->render(cam, list.data(), list.size(), &stats));
    ASSERT_TRUE(r->readPixels(img.data()));
  }
  g_allocations = 0;
  g_counting = true;
  for (int i = 0; i < 5; ++i) {
    cam.heading_deg = i * 5.0;
    r->render(cam, list.data(), list.size(), &stats);
    r->readPixels(img.data());
  }
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0u);

  // The counter itself works.
  g_counting = true;
  auto probe = std::make_unique<int>(1);
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 1u);
  EXPECT_GT(stats.meshes_drawn, 0u);
}

}  // namespace
}  // namespace blvd::render
