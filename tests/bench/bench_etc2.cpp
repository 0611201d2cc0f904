// Google Benchmark: ETC2 RGB8 encoding and decoding of a 512 × 512 image
// (smooth gradients with texture noise, as impostor atlases are), the cost a
// loader thread would pay to transcode a cell's textures (docs/decisions/0014).
#include <benchmark/benchmark.h>

#include <cstdint>
#include <random>
#include <vector>

#include "render/etc2.h"

namespace {

constexpr int kSize = 512;

std::vector<uint8_t> image() {
  std::vector<uint8_t> img(size_t(kSize) * kSize * 4);
  std::mt19937 rng(1);
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      uint8_t* p = &img[(size_t(y) * kSize + x) * 4];
      p[0] = uint8_t(x / 2);
      p[1] = uint8_t(y / 2);
      p[2] = uint8_t((x + y) / 4 + (rng() & 15));
      p[3] = 255;
    }
  return img;
}

void BM_Encode(benchmark::State& state) {
  const std::vector<uint8_t> img = image();
  std::vector<uint8_t> out(blvd::render::etc2Bytes(kSize, kSize));
  for (auto _ : state) {
    blvd::render::encodeEtc2(img.data(), kSize, kSize, size_t(kSize) * 4, out.data());
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["Mpixel/s"] = benchmark::Counter(double(kSize) * kSize * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Encode)->Unit(benchmark::kMillisecond);

void BM_Decode(benchmark::State& state) {
  const std::vector<uint8_t> img = image();
  std::vector<uint8_t> enc(blvd::render::etc2Bytes(kSize, kSize)), out(img.size());
  blvd::render::encodeEtc2(img.data(), kSize, kSize, size_t(kSize) * 4, enc.data());
  for (auto _ : state) {
    blvd::render::decodeEtc2(enc.data(), kSize, kSize, out.data());
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["Mpixel/s"] = benchmark::Counter(double(kSize) * kSize * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Decode)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
