// RGBA8 images on disk (PNG through stb) and the PSNR used by the fidelity
// measurements and the golden-image tests. Images are tightly packed, top row
// first, 4 bytes a pixel.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace blvd::imaging {

// Writes an RGBA8 PNG. False with `err` set when the file cannot be written.
bool writePng(const std::string& path, int width, int height, const uint8_t* rgba,
              std::string& err);

// Reads any PNG stb understands, converted to RGBA8.
bool readPng(const std::string& path, int& width, int& height, std::vector<uint8_t>& rgba,
             std::string& err);

// Peak signal-to-noise ratio in dB over the R, G and B channels (alpha is
// ignored) of two RGBA8 images of `pixels` pixels each. +infinity when they
// are equal (also for pixels == 0).
double psnr(const uint8_t* a, const uint8_t* b, size_t pixels);

}  // namespace blvd::imaging
