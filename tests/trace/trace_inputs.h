// What a host feeds from a recorded drive: the NMEA log's fixes (through the
// gnss adapter, via the replayer's decoder and clock) and the candump log's raw
// frames, merged in time order (a fix first on a tie, as the replayer does),
// and sim_feed's ground-truth CSV. Shared by the trace tests.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "blvd/blvd.h"
#include "can/frame.h"

namespace blvd::trace_test {

struct Truth {
  double t;
  uint32_t cell;
};

// sim_feed's truth CSV (t, e, n, lat, lon, heading_deg, speed_mps, cell, arc_m, fix); test failures on bad rows.
std::vector<Truth> readTruth(const std::string& path);

struct Input {
  double t;
  bool gnss;
  blvd_gnss_fix fix;  // when gnss
  can::Frame frame;   // otherwise
};

// Both logs, strictly parsed (a bad line is a test failure), merged by time.
std::vector<Input> readInputs(const std::string& nmea_path, const std::string& candump_path);

// Feeds one input: blvd_feed_gnss, or blvd_feed_can_frame through `profile`.
blvd_status feed(blvd_runtime* rt, blvd_can_profile* profile, const Input& in);

// A Toyota profile on the repository's DBC (null with a test failure).
blvd_can_profile* createToyotaProfile();

}  // namespace blvd::trace_test
