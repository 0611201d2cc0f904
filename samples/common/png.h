// Headless frames as PNG files (stb_image_write), for the samples that write frames.
#pragma once

#include <cstdint>
#include <string>

namespace samples {

// Writes tightly packed RGBA8, top row first. False when the file cannot be written.
bool writePng(const std::string& path, const unsigned char* rgba, uint32_t width, uint32_t height);

// True when every pixel has the same colour (a frame that drew nothing).
bool isBlank(const unsigned char* rgba, uint32_t width, uint32_t height);

}  // namespace samples
