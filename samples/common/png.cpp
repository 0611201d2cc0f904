#include "common/png.h"

#include <cstring>

// libblvd keeps its own stb copy hidden, so the samples have their own. The stb
// folder is a SYSTEM include (CMakeLists.txt): its warnings are not ours.
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb_image_write.h>

namespace samples {

bool writePng(const std::string& path, const unsigned char* rgba, uint32_t width, uint32_t height) {
  return stbi_write_png(path.c_str(), static_cast<int>(width), static_cast<int>(height), 4, rgba,
                        static_cast<int>(width * 4)) != 0;
}

bool isUniform(const unsigned char* rgba, uint32_t width, uint32_t height) {
  const size_t n = static_cast<size_t>(width) * height;
  for (size_t i = 1; i < n; ++i)
    if (std::memcmp(rgba + 4 * i, rgba, 4) != 0) return false;
  return true;
}

bool isBlank(const unsigned char* rgba, uint32_t width, uint32_t height, uint64_t triangles) {
  if (!isUniform(rgba, width, height)) return false;
  const bool black = width * height == 0 || (rgba[0] < 8 && rgba[1] < 8 && rgba[2] < 8);
  return triangles == 0 || black;
}

}  // namespace samples
