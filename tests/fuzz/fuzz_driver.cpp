// Stand-in for libFuzzer's main() when the compiler is not Clang: runs
// LLVMFuzzerTestOneInput over the files (and the files in the directories)
// named on the command line, and over variations of each one: truncations
// (every one of a small input) and single-byte flips. Every input is copied into a heap buffer
// of exactly its size, as libFuzzer does, so ASan catches a read past the end.
// Arguments starting with '-' (libFuzzer flags such as -runs=0) are ignored,
// so CTest can call both kinds of binary the same way, but for
// -max_variations=N: at most N truncations and N flips an input, for a target
// whose every run costs milliseconds (one that creates a GL context).
//
// Usage: fuzz_<target> [-flags] FILE_OR_DIR...
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);
extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) __attribute__((weak));

namespace {

size_t g_runs = 0;
size_t g_max_variations = 4096;  // -max_variations=N

void runOne(const uint8_t* data, size_t size) {
  // Exactly `size` bytes on the heap; new[] of 0 still gives a unique pointer.
  std::unique_ptr<uint8_t[]> copy(new uint8_t[size]);
  if (size) std::memcpy(copy.get(), data, size);
  LLVMFuzzerTestOneInput(copy.get(), size);
  ++g_runs;
}

// Variations of an input read about this many bytes in all (each truncation
// and flip is read whole), so that a larger input gets fewer, evenly spread,
// and no seed file costs minutes under the sanitizers.
constexpr size_t kBytesPerInput = size_t(8) << 20;

void runVariations(const std::vector<uint8_t>& in) {
  runOne(in.data(), in.size());
  const size_t budget = kBytesPerInput / std::max<size_t>(in.size(), 1);
  // Every truncation for inputs up to 2 KiB, then at least 64 evenly spread.
  const size_t cuts = std::min(std::clamp<size_t>(budget, 64, 4096), g_max_variations);
  const size_t step = std::max<size_t>(1, in.size() / cuts);
  for (size_t n = 0; n < in.size(); n += step) runOne(in.data(), n);
  // Single-byte flips at up to 512 evenly spread positions, at least 32.
  std::vector<uint8_t> flipped = in;
  const size_t fstep = std::max<size_t>(1, in.size() / std::min(std::clamp<size_t>(budget, 32, 512), g_max_variations));
  for (size_t i = 0; i < in.size(); i += fstep) {
    flipped[i] ^= 0xFF;
    runOne(flipped.data(), flipped.size());
    flipped[i] ^= 0xFF;
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (LLVMFuzzerInitialize) LLVMFuzzerInitialize(&argc, &argv);
  std::vector<std::filesystem::path> files;
  for (int i = 1; i < argc; ++i) {
    if (std::strncmp(argv[i], "-max_variations=", 16) == 0) g_max_variations = std::max(1, std::atoi(argv[i] + 16));
    if (argv[i][0] == '-') continue;
    const std::filesystem::path p = argv[i];
    std::error_code ec;
    if (std::filesystem::is_directory(p, ec)) {
      for (const auto& e : std::filesystem::recursive_directory_iterator(p, ec))
        if (e.is_regular_file()) files.push_back(e.path());
    } else if (std::filesystem::is_regular_file(p, ec)) {
      files.push_back(p);
    } else {
      std::fprintf(stderr, "%s: no such file or directory\n", argv[i]);
      return 2;
    }
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) {
    std::fprintf(stderr, "%s: no input files (usage: %s FILE_OR_DIR...)\n", argv[0], argv[0]);
    return 2;
  }
  for (const auto& f : files) {
    std::ifstream in(f, std::ios::binary);
    const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const size_t before = g_runs;
    runVariations(bytes);
    std::printf("%s: %zu bytes, %zu runs\n", f.c_str(), bytes.size(), g_runs - before);
  }
  std::printf("%zu files, %zu runs, no crash\n", files.size(), g_runs);
  return 0;
}
