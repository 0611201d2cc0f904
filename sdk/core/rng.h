// A seeded random source that gives the same numbers with every standard
// library: std::mt19937_64 is specified to the bit, its distributions are
// not (std::uniform_real_distribution, std::normal_distribution differ
// between libstdc++ and libc++), so uniform() and gauss() are written here.
// The simulator's noise and the seeded routes draw from it.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>

#include "core/math.h"

namespace blvd::core {

class Rng {
 public:
  explicit Rng(uint64_t seed) : g_(seed) {}
  uint64_t next() { return g_(); }
  // [0, 1), 53 random bits.
  double uniform() { return static_cast<double>(g_() >> 11) * (1.0 / 9007199254740992.0); }
  // Standard normal (Box-Muller, one value per call).
  double gauss() {
    double u1 = uniform();
    if (u1 < 1e-300) u1 = 1e-300;
    return std::sqrt(-2 * std::log(u1)) * std::cos(2 * kPi * uniform());
  }

 private:
  std::mt19937_64 g_;
};

}  // namespace blvd::core
