#include "trace_inputs.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <sstream>

#include "can/candump.h"
#include "can/to_blvd.h"
#include "replay/replayer.h"

namespace blvd::trace_test {

std::vector<Truth> readTruth(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line.rfind("t,e,n,lat,lon,heading_deg,speed_mps,cell,arc_m,fix", 0), 0u) << path;
  std::vector<Truth> rows;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream ls(line);
    for (std::string x; std::getline(ls, x, ',');) f.push_back(x);
    if (f.size() != 10) {
      ADD_FAILURE() << path << ": bad row " << line;
      continue;
    }
    rows.push_back({std::stod(f[0]), static_cast<uint32_t>(std::stoul(f[7]))});
  }
  return rows;
}

std::vector<Input> readInputs(const std::string& nmea_path, const std::string& candump_path) {
  std::vector<Input> in;
  replay::ReplayDesc rd;
  rd.nmea_path = nmea_path;
  rd.strict = true;
  replay::Replayer r;
  std::string err;
  EXPECT_EQ(r.open(rd, err), BLVD_OK) << err;
  replay::Event ev;
  while (r.next(ev) == replay::Replayer::Step::Event) in.push_back({ev.t, true, ev.gnss, {}});
  EXPECT_TRUE(r.error().empty()) << r.error();
  can::CandumpReader reader;
  EXPECT_EQ(reader.open(candump_path), BLVD_OK) << reader.error();
  can::Record rec;
  for (;;) {
    const auto res = reader.next(rec);
    if (res == can::CandumpReader::Result::End) break;
    EXPECT_EQ(res, can::CandumpReader::Result::Frame) << reader.error();
    if (res != can::CandumpReader::Result::Frame) break;
    in.push_back({rec.frame.t, false, {}, rec.frame});
  }
  std::stable_sort(in.begin(), in.end(), [](const Input& a, const Input& b) {
    return a.t < b.t || (a.t == b.t && a.gnss && !b.gnss);
  });
  return in;
}

blvd_status feed(blvd_runtime* rt, blvd_can_profile* profile, const Input& in) {
  if (in.gnss) return blvd_feed_gnss(rt, &in.fix);
  const blvd_can_frame f = can::toBlvd(in.frame);
  return blvd_feed_can_frame(rt, profile, &f);
}

blvd_can_profile* createToyotaProfile() {
  blvd_can_profile_desc pd{};
  pd.struct_size = sizeof pd;
  pd.vehicle = BLVD_VEHICLE_TOYOTA;
  pd.dbc_path = BLVD_TEST_DATA_DIR "/can/dbc/toyota_new_mc_pt_generated.dbc";
  blvd_can_profile* prof = nullptr;
  EXPECT_EQ(blvd_can_profile_create(&pd, &prof), BLVD_OK) << blvd_last_error(nullptr);
  return prof;
}

}  // namespace blvd::trace_test
