// Context backends: each one on this machine, the BLVD_BACKEND override, and
// the reasons given when a backend cannot be had.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>

#include "render/context.h"
#include "render/gl_api.h"

namespace blvd::render {
namespace {

// Restores BLVD_BACKEND when a test that changed it ends.
class EnvGuard {
 public:
  EnvGuard() {
    const char* v = std::getenv("BLVD_BACKEND");
    had_ = v != nullptr;
    if (had_) old_ = v;
  }
  ~EnvGuard() {
    if (had_) {
      setenv("BLVD_BACKEND", old_.c_str(), 1);
    } else {
      unsetenv("BLVD_BACKEND");
    }
  }

 private:
  bool had_ = false;
  std::string old_;
};

void expectGlWorks(Context& ctx) {
  GlApi gl;
  std::string missing;
  ASSERT_TRUE(gl.load(ctx, missing)) << missing;
  const char* version = reinterpret_cast<const char*>(gl.GetString(GL_VERSION));
  ASSERT_NE(version, nullptr);
  const bool gles = std::strncmp(version, "OpenGL ES", 9) == 0;
  EXPECT_EQ(gles, ctx.isGles()) << version;
  std::printf("%s: %s | %s\n", ctx.name(), version,
              reinterpret_cast<const char*>(gl.GetString(GL_RENDERER)));
}

TEST(Context, EglSurfaceless) {
  std::string why;
  auto ctx = createContext(Backend::EglSurfaceless, why);
  ASSERT_NE(ctx, nullptr) << why;
  EXPECT_STREQ(ctx->name(), "egl-surfaceless");
  EXPECT_TRUE(ctx->isGles());
  EXPECT_FALSE(ctx->isShared());
  EXPECT_TRUE(ctx->makeCurrent());
  expectGlWorks(*ctx);
}

TEST(Context, EglDevice) {
  std::string why;
  auto ctx = createContext(Backend::EglDevice, why);
  if (!ctx) GTEST_SKIP() << "egl-device unavailable here: " << why;
  EXPECT_STREQ(ctx->name(), "egl-device");
  expectGlWorks(*ctx);
}

TEST(Context, OSMesa) {
  std::string why;
  auto ctx = createContext(Backend::OSMesa, why);
  ASSERT_NE(ctx, nullptr) << why;
  EXPECT_STREQ(ctx->name(), "osmesa");
  EXPECT_FALSE(ctx->isGles());
  expectGlWorks(*ctx);
}

TEST(Context, AutoPicksSomething) {
  EnvGuard env;
  unsetenv("BLVD_BACKEND");
  std::string why;
  auto ctx = createContext(Backend::Auto, why);
  ASSERT_NE(ctx, nullptr) << why;
  std::printf("auto chose %s\n", ctx->name());
}

TEST(Context, EnvOverrideNarrowsAuto) {
  EnvGuard env;
  setenv("BLVD_BACKEND", "osmesa", 1);
  std::string why;
  auto ctx = createContext(Backend::Auto, why);
  ASSERT_NE(ctx, nullptr) << why;
  EXPECT_STREQ(ctx->name(), "osmesa");
  ctx.reset();
  // An explicit backend ignores the override.
  auto egl = createContext(Backend::EglSurfaceless, why);
  ASSERT_NE(egl, nullptr) << why;
  EXPECT_STREQ(egl->name(), "egl-surfaceless");
}

TEST(Context, EnvOverrideRejectsUnknownName) {
  EnvGuard env;
  setenv("BLVD_BACKEND", "vulkan", 1);
  std::string why;
  EXPECT_EQ(createContext(Backend::Auto, why), nullptr);
  EXPECT_NE(why.find("BLVD_BACKEND=vulkan"), std::string::npos) << why;
}

TEST(Context, SharedNeedsACurrentContext) {
  std::string why;
  EXPECT_EQ(createContext(Backend::Shared, why), nullptr);
  EXPECT_NE(why.find("shared:"), std::string::npos) << why;
}

TEST(Context, BackendNamesRoundTrip) {
  for (Backend b : {Backend::Auto, Backend::EglSurfaceless, Backend::EglDevice, Backend::OSMesa,
                    Backend::Shared}) {
    Backend parsed = Backend::Auto;
    ASSERT_TRUE(parseBackend(backendName(b), parsed)) << backendName(b);
    EXPECT_EQ(parsed, b);
  }
  Backend parsed = Backend::Auto;
  EXPECT_FALSE(parseBackend("gles", parsed));
  EXPECT_FALSE(parseBackend(nullptr, parsed));
  // The C API casts blvd_backend to Backend.
  EXPECT_EQ(static_cast<int>(Backend::Shared), 4);
}

// A context that offers no GL at all: load() must name what is missing.
class NoGl final : public Context {
 public:
  bool makeCurrent() override { return true; }
  const char* name() const override { return "none"; }
  void* getProcAddress(const char* fn) override {
    return std::strcmp(fn, "glGenVertexArrays") == 0 ? nullptr : reinterpret_cast<void*>(&dummy);
  }
  bool isGles() const override { return true; }
  static void dummy() {}
};

TEST(GlApi, ReportsMissingEntryPointsByName) {
  NoGl ctx;
  GlApi gl;
  std::string missing;
  EXPECT_FALSE(gl.load(ctx, missing));
  EXPECT_EQ(missing, "glGenVertexArrays");
  EXPECT_NE(gl.CreateShader, nullptr);
}

}  // namespace
}  // namespace blvd::render
