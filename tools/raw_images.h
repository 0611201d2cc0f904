// Raw RGBA8 images named on a command line as FILE WIDTH HEIGHT triples
// (tools/layer_images.py prints them), for the codec measurement programs.
#pragma once
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

struct RawImage {
  int w = 0, h = 0;
  std::vector<uint8_t> rgba;
};

// The images of argv[1..argc); exits with status 2, naming the file, when one
// cannot be read, or with a usage line when there is none.
inline std::vector<RawImage> readRawImages(int argc, char** argv, const char* who) {
  std::vector<RawImage> images;
  for (int a = 1; a + 2 < argc; a += 3) {
    RawImage im;
    im.w = std::atoi(argv[a + 1]), im.h = std::atoi(argv[a + 2]);
    im.rgba.resize(size_t(im.w > 0 ? im.w : 0) * size_t(im.h > 0 ? im.h : 0) * 4);
    FILE* f = std::fopen(argv[a], "rb");
    const bool ok = f && !im.rgba.empty() && std::fread(im.rgba.data(), 1, im.rgba.size(), f) == im.rgba.size();
    if (f) std::fclose(f);
    if (!ok) {
      std::fprintf(stderr, "%s: cannot read %d x %d RGBA8 from %s\n", who, im.w, im.h, argv[a]);
      std::exit(2);
    }
    images.push_back(std::move(im));
  }
  if (images.empty()) {
    std::fprintf(stderr, "usage: %s FILE WIDTH HEIGHT [FILE WIDTH HEIGHT ...]\n", who);
    std::exit(2);
  }
  return images;
}
