// Headless frames as PNG files (stb_image_write), for the samples that write frames.
#pragma once

#include <cstdint>
#include <string>

namespace samples {

// Writes tightly packed RGBA8, top row first. False when the file cannot be written.
bool writePng(const std::string& path, const unsigned char* rgba, uint32_t width, uint32_t height);

// True when every pixel has the same colour.
bool isUniform(const unsigned char* rgba, uint32_t width, uint32_t height);

// A frame that shows nothing: one colour and no triangle drawn, or all black
// (a failed render). One colour with geometry drawn is a real view (a wall
// filling it) and is not blank.
bool isBlank(const unsigned char* rgba, uint32_t width, uint32_t height, uint64_t triangles);

}  // namespace samples
