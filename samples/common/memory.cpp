#include "common/memory.h"

#include <nlohmann/json.hpp>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>

namespace samples {
namespace {

// A "Key:   N kB" line of /proc/self/status in bytes; -1 when absent.
long long statusBytes(const char* key) {
  std::ifstream f("/proc/self/status");
  const size_t n = std::strlen(key);
  for (std::string line; std::getline(f, line);)
    if (line.compare(0, n, key) == 0) return std::strtoll(line.c_str() + n, nullptr, 10) * 1024;
  return -1;
}

nlohmann::json pool(const blvd_pool_stats& p) {
  return {{"capacity_bytes", p.capacity_bytes}, {"used_bytes", p.used_bytes}, {"high_water_bytes", p.high_water_bytes}};
}

}  // namespace

void addMemoryStats(nlohmann::json& j, const blvd_stats* rt) {
  nlohmann::json m;
  m["rss_bytes"] = statusBytes("VmRSS:");
  m["rss_peak_bytes"] = statusBytes("VmHWM:");
  if (rt) {
    m["resident_cells"] = rt->resident_cells;
    m["max_resident_cells"] = rt->max_resident_cells;
    m["gpu"] = pool(rt->gpu);
    m["staging"] = pool(rt->staging);
    m["decode_high_water_bytes"] = rt->decode.high_water_bytes;
    m["table_bytes"] = rt->table_bytes;
    m["tracking_bytes"] = rt->tracking_bytes;
    m["loads"] = rt->loads;
    m["evictions"] = rt->evictions;
    m["misses"] = rt->misses;
    m["load_errors"] = rt->load_errors;
  }
  j["memory"] = m;
}

}  // namespace samples
