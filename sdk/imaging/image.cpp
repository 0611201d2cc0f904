// PNG I/O and PSNR. The stb implementation lives in stb_impl.cpp.
#include "imaging/image.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <stb_image.h>
#include <stb_image_write.h>

namespace blvd::imaging {

bool writePng(const std::string& path, int width, int height, const uint8_t* rgba,
              std::string& err) {
  if (width <= 0 || height <= 0 || !rgba) {
    err = "writePng: empty image for " + path;
    return false;
  }
  if (!stbi_write_png(path.c_str(), width, height, 4, rgba, width * 4)) {
    err = "writePng: cannot write " + path;
    return false;
  }
  return true;
}

bool readPng(const std::string& path, int& width, int& height, std::vector<uint8_t>& rgba,
             std::string& err) {
  int w = 0, h = 0, channels = 0;
  stbi_uc* data = stbi_load(path.c_str(), &w, &h, &channels, 4);
  if (!data) {
    const char* reason = stbi_failure_reason();
    err = "readPng: " + path + ": " + (reason ? reason : "unknown error");
    return false;
  }
  width = w;
  height = h;
  rgba.assign(data, data + static_cast<size_t>(w) * static_cast<size_t>(h) * 4);
  stbi_image_free(data);
  return true;
}

double psnr(const uint8_t* a, const uint8_t* b, size_t pixels) {
  // Integer sum of squares: exact, and 2^64 covers 10^13 pixels.
  uint64_t sse = 0;
  for (size_t i = 0; i < pixels; ++i) {
    for (int c = 0; c < 3; ++c) {
      const int d = int{a[i * 4 + c]} - int{b[i * 4 + c]};
      sse += static_cast<uint64_t>(d * d);
    }
  }
  if (sse == 0) return std::numeric_limits<double>::infinity();
  const double mse = static_cast<double>(sse) / (static_cast<double>(pixels) * 3.0);
  return 10.0 * std::log10(255.0 * 255.0 / mse);
}

}  // namespace blvd::imaging
