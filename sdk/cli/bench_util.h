// Helpers shared by the `blvd bench` subcommands: percentiles, C API status
// checks and a drive of a runtime along a route.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "blvd/blvd.h"
#include "core/status.h"

namespace blvd::cli {

// Linear-interpolated percentile p (0..100) of the finite values; NaN if none.
inline double pct(std::vector<double> v, double p) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); }), v.end());
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const double idx = p / 100.0 * double(v.size() - 1);
  const size_t i = static_cast<size_t>(idx);
  const double f = idx - double(i);
  return i + 1 < v.size() ? v[i] * (1 - f) + v[i + 1] * f : v[i];
}

// Throws core::Error with blvd_last_error's text when st is not BLVD_OK.
inline void check(blvd_status st, blvd_runtime* rt, const char* what) {
  if (st != BLVD_OK) throw core::Error(static_cast<core::Status>(st), std::string(what) + ": " + blvd_last_error(rt));
}

// "WIDTHxHEIGHT" (each at least 16) or throws InvalidArg naming --size.
inline void parseSize(const std::string& s, int& w, int& h) {
  if (std::sscanf(s.c_str(), "%dx%d", &w, &h) != 2 || w < 16 || h < 16)
    throw core::Error(core::Status::InvalidArg, "--size must be WIDTHxHEIGHT");
}

// "auto:N" (N > 0) -> N, or throws InvalidArg naming --route.
inline unsigned parseAutoRoute(const std::string& s) {
  unsigned n = 0;
  if (std::sscanf(s.c_str(), "auto:%u", &n) != 1 || n == 0)
    throw core::Error(core::Status::InvalidArg, "--route must be auto:N");
  return n;
}

// Writes `text` and a newline to `path` (no-op for an empty path).
inline void writeText(const std::string& path, const std::string& text) {
  if (path.empty()) return;
  std::FILE* f = std::fopen(path.c_str(), "w");
  const bool ok = f && std::fputs(text.c_str(), f) >= 0 && std::fputc('\n', f) != EOF;
  if (f) std::fclose(f);
  if (!ok) throw core::Error(core::Status::Io, "cannot write " + path);
}

}  // namespace blvd::cli
