// Resident memory for the samples' stats JSON (vcan_drive, gnss_replay): the process's resident set
// (/proc/self/status) and, with a C API runtime, what blvd_runtime_stats says
// blvd holds (resident cells, its pools, package tables, tracker).
#pragma once

#include <nlohmann/json_fwd.hpp>

#include "blvd/blvd.h"

namespace samples {

// j["memory"] = {"rss_bytes", "rss_peak_bytes"} (-1 where /proc is missing) and,
// when `rt` is not null, the runtime's residency and pool figures.
void addMemoryStats(nlohmann::json& j, const blvd_stats* rt);

}  // namespace samples
