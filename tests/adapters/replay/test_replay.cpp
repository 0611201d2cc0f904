// Replay adapter: merging, the comma2k19 check through the replayer, NMEA replay
// against direct decoding, record -> replay, real-time pacing, determinism.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

#include "can/candump.h"
#include "vehicle/dbc.h"
#include "can_test_util.h"
#include "replay/recorder.h"
#include "replay/replayer.h"

namespace blvd::replay {
namespace {

const std::string kToyotaDbc = can::test::dataPath("dbc/toyota_new_mc_pt_generated.dbc");

struct Capture final : Sink {
  std::vector<Event> events;
  void onEvent(const Event& e) override { events.push_back(e); }
};

blvd_gnss_fix makeFix(double t, double lat, double lon) {
  blvd_gnss_fix f{};
  f.struct_size = sizeof f;
  f.t = t;
  f.lat = lat;
  f.lon = lon;
  f.alt = 42.5;
  f.speed_mps = 10.0f;
  f.track_deg = 211.0f;
  f.hdop = 0.9f;
  f.mode = BLVD_GNSS_MODE_3D;
  f.flags = BLVD_GNSS_HAS_TIME | BLVD_GNSS_HAS_LATLON | BLVD_GNSS_HAS_ALT | BLVD_GNSS_HAS_SPEED |
            BLVD_GNSS_HAS_TRACK | BLVD_GNSS_HAS_HDOP;
  return f;
}

// n fixes one second apart from t0 (UTC, 2024), written through the Recorder.
std::string nmeaTrace(double t0, int n) {
  std::ostringstream out;
  Recorder rec;
  rec.attachNmea(out);
  for (int k = 0; k < n; ++k) EXPECT_TRUE(rec.record(makeFix(t0 + k, 43.73537 - 1e-5 * k, 7.41729 - 1e-5 * k)));
  return out.str();
}

// Toyota WHEEL_SPEEDS frames, every wheel at `kmh`, at candump times t0 + k * dt.
std::string wheelTrace(double t0, double dt, int n, double kmh) {
  vehicle::Database db;
  std::string err;
  EXPECT_EQ(db.load(kToyotaDbc, err), blvd::core::Status::Ok) << err;
  const vehicle::Message* m = db.findByName("WHEEL_SPEEDS");
  EXPECT_NE(m, nullptr);
  std::ostringstream out;
  Recorder rec;
  rec.attachCandump(out);
  for (int k = 0; k < n && m; ++k) {
    can::Frame f;
    f.dlc = 8;
    f.iface = "can0";
    f.t = t0 + k * dt;
    EXPECT_EQ(vehicle::encode(*m,
                          {{"WHEEL_SPEED_FL", kmh}, {"WHEEL_SPEED_FR", kmh}, {"WHEEL_SPEED_RL", kmh},
                           {"WHEEL_SPEED_RR", kmh}},
                          f, err),
              blvd::core::Status::Ok)
        << err;
    EXPECT_TRUE(rec.record(f));
  }
  return out.str();
}

std::vector<Event> replayAll(ReplayDesc d) {
  Replayer r;
  std::string err;
  EXPECT_EQ(r.open(d, err), BLVD_OK) << err;
  Capture c;
  EXPECT_EQ(r.run(c, err), BLVD_OK) << err;
  return c.events;
}

// Every bit of an event, as text, for exact comparisons (NaN included).
std::string dump(const std::vector<Event>& ev) {
  std::string s;
  char buf[512];
  for (const Event& e : ev) {
    if (e.type == EventType::Gnss) {
      const blvd_gnss_fix& g = e.gnss;
      std::snprintf(buf, sizeof buf, "G %a %a %a %a %a %a %a %a %d %u %llu\n", e.t, g.lat, g.lon, g.alt,
                    double(g.speed_mps), double(g.track_deg), double(g.hdop), double(g.h_acc_m), g.mode, g.flags,
                    static_cast<unsigned long long>(e.line));
    } else {
      const blvd_odometry& o = e.odometry;
      std::snprintf(buf, sizeof buf, "O %a %a %a %a %a %a %a %d %u %llu\n", e.t, o.speed_mps, o.yaw_rate_dps,
                    o.wheel_speeds_mps[0], o.wheel_speeds_mps[1], o.wheel_speeds_mps[2], o.wheel_speeds_mps[3],
                    o.reverse, o.flags, static_cast<unsigned long long>(e.line));
    }
    s += buf;
  }
  return s;
}

constexpr double kT0 = 1717243200.0;  // 2024-06-01T12:00:00Z

TEST(Replay, MergesBothStreamsByTime) {
  std::istringstream nmea(nmeaTrace(kT0, 5));
  std::istringstream can(wheelTrace(100.25, 0.5, 10, 36.0));
  ReplayDesc d;
  d.nmea_stream = &nmea;
  d.candump_stream = &can;
  d.dbc_path = kToyotaDbc;
  d.has_offset = true;
  d.offset_s = kT0 - 100.0;  // candump 100.25 -> kT0 + 0.25
  const std::vector<Event> ev = replayAll(d);
  ASSERT_EQ(ev.size(), 15u);
  size_t gnss = 0, odo = 0;
  for (size_t i = 0; i < ev.size(); ++i) {
    if (i) {
      EXPECT_LE(ev[i - 1].t, ev[i].t) << i;
    }
    if (ev[i].type == EventType::Gnss) {
      ++gnss;
      EXPECT_EQ(ev[i].t, ev[i].gnss.t);
    } else {
      ++odo;
      EXPECT_EQ(ev[i].t, ev[i].odometry.t);
      EXPECT_NEAR(ev[i].odometry.speed_mps, 10.0, 0.01);
      EXPECT_TRUE(ev[i].odometry.flags & BLVD_ODO_SPEED);
    }
  }
  EXPECT_EQ(gnss, 5u);
  EXPECT_EQ(odo, 10u);
  // Fix, odo (0.25), odo (0.75), fix (1.0), ...
  EXPECT_EQ(ev[0].type, EventType::Gnss);
  EXPECT_EQ(ev[1].type, EventType::Odometry);
  EXPECT_NEAR(ev[1].t - kT0, 0.25, 1e-6);
  EXPECT_EQ(ev[2].type, EventType::Odometry);
  EXPECT_EQ(ev[3].type, EventType::Gnss);
}

TEST(Replay, DefaultOffsetAlignsFirstEvents) {
  std::istringstream nmea(nmeaTrace(kT0, 3));
  std::istringstream can(wheelTrace(5000.0, 1.0, 3, 18.0));
  ReplayDesc d;
  d.nmea_stream = &nmea;
  d.candump_stream = &can;
  d.dbc_path = kToyotaDbc;
  Replayer r;
  std::string err;
  ASSERT_EQ(r.open(d, err), BLVD_OK) << err;
  Capture c;
  ASSERT_EQ(r.run(c, err), BLVD_OK) << err;
  EXPECT_DOUBLE_EQ(r.offset(), kT0 - 5000.0);
  ASSERT_EQ(c.events.size(), 6u);
  EXPECT_EQ(c.events[0].type, EventType::Gnss);  // a tie: the fix first
  EXPECT_EQ(c.events[1].type, EventType::Odometry);
  EXPECT_NEAR(c.events[1].t, kT0, 1e-6);
}

TEST(Replay, Comma2k19SpeedsMatchReference) {
  // Sampled rows of comma's reference CSV (t_boot_s -> speed_mps).
  std::map<long long, double> want;
  {
    std::istringstream in(can::test::readFile(can::test::dataPath("comma2k19_rav4_seg40_can_reference.csv")));
    std::string line;
    std::getline(in, line);
    for (int row = 0; std::getline(in, line); ++row) {
      if (row % 997 != 0) continue;
      const size_t c1 = line.find(','), c2 = line.find(',', c1 + 1);
      want[std::llround(std::stod(line.substr(0, c1)) * 1e6)] = std::stod(line.substr(c1 + 1, c2 - c1 - 1));
    }
  }
  ASSERT_GE(want.size(), 4u);

  struct Last final : Sink {
    std::map<long long, double> speed;  // last odometry speed at each microsecond
    uint64_t n = 0;
    void onEvent(const Event& e) override {
      ASSERT_EQ(e.type, EventType::Odometry);
      ++n;
      speed[std::llround(e.t * 1e6)] = e.odometry.speed_mps;
    }
  } sink;
  std::istringstream log(can::test::comma2k19Candump());
  ReplayDesc d;
  d.candump_path = "comma2k19_rav4_seg40_candump.log";
  d.candump_stream = &log;
  d.dbc_path = kToyotaDbc;
  d.vehicle = "toyota";
  Replayer r;
  std::string err;
  ASSERT_EQ(r.open(d, err), BLVD_OK) << err;
  ASSERT_EQ(r.run(sink, err), BLVD_OK) << err;
  EXPECT_EQ(r.offset(), 0.0);  // one stream: its own clock
  EXPECT_GT(sink.n, 4000u);
  EXPECT_EQ(r.stats().bad_lines, 0u);
  for (const auto& [us, v] : want) {
    auto it = sink.speed.find(us);
    ASSERT_NE(it, sink.speed.end()) << "no odometry at t=" << us * 1e-6;
    EXPECT_NEAR(it->second, v, 1e-5) << "t=" << us * 1e-6;
  }
}

// A log from tests/data/nmea gives, through the replayer, the dated fixes a direct decode gives.
TEST(Replay, NmeaLogMatchesDirectDecode) {
  const std::string path = std::string(BLVD_TEST_DATA_DIR) + "/nmea/ublox-zed-f9p-nmea.log";
  struct Direct final : gnss::NmeaDecoder::Handler {
    std::vector<gnss::Fix> fixes;
    void onFix(const gnss::Fix& f) override {
      if (f.flags & gnss::kFixHasTime) fixes.push_back(f);
    }
    void onDiagnostic(const gnss::NmeaDiagnostic&) override {}
  } direct;
  gnss::NmeaDecoder dec;
  const std::string text = can::test::readFile(path);
  dec.feed(text.data(), text.size(), direct);
  dec.finish(direct);
  ASSERT_GT(direct.fixes.size(), 5u);

  ReplayDesc d;
  d.nmea_path = path;
  const std::vector<Event> ev = replayAll(d);
  ASSERT_EQ(ev.size(), direct.fixes.size());
  for (size_t i = 0; i < ev.size(); ++i) {
    const blvd_gnss_fix want = toBlvd(direct.fixes[i]);
    ASSERT_EQ(ev[i].type, EventType::Gnss);
    EXPECT_EQ(ev[i].gnss.t, want.t) << i;
    EXPECT_EQ(ev[i].gnss.flags, want.flags) << i;
    if (want.flags & BLVD_GNSS_HAS_LATLON) {
      EXPECT_EQ(ev[i].gnss.lat, want.lat) << i;
      EXPECT_EQ(ev[i].gnss.lon, want.lon) << i;
    }
    EXPECT_EQ(ev[i].gnss.mode, want.mode) << i;
  }
}

TEST(Replay, RecordThenReplayRoundTrip) {
  const double lats[] = {43.73537, -33.8688197, 0.0000001, 89.9999999, 43.7301234};
  const double lons[] = {7.41729, 151.2092955, -0.0000001, -179.9999999, 7.4199876};
  std::ostringstream out;
  Recorder rec;
  rec.attachNmea(out);
  for (int k = 0; k < 5; ++k) {
    blvd_gnss_fix f = makeFix(kT0 + 0.2 * k, lats[k], lons[k]);
    f.h_acc_m = 1.5f;
    f.flags |= BLVD_GNSS_HAS_HACC;
    ASSERT_TRUE(rec.record(f));
  }
  EXPECT_EQ(rec.fixes(), 5u);
  // Every line carries a correct checksum.
  std::istringstream lines(out.str());
  for (std::string l; std::getline(lines, l);) {
    ASSERT_GE(l.size(), 6u);
    ASSERT_EQ(l.back(), '\r');
    const size_t star = l.find('*');
    ASSERT_NE(star, std::string::npos);
    char hex[3];
    std::snprintf(hex, sizeof hex, "%02X", nmeaChecksum(std::string_view(l).substr(1, star - 1)));
    EXPECT_EQ(l.substr(star + 1, 2), hex) << l;
  }
  std::istringstream in(out.str());
  ReplayDesc d;
  d.nmea_stream = &in;
  d.strict = true;
  Replayer r;
  std::string err;
  ASSERT_EQ(r.open(d, err), BLVD_OK) << err;
  Capture c;
  ASSERT_EQ(r.run(c, err), BLVD_OK) << err;
  EXPECT_TRUE(r.warnings().empty()) << r.warnings().front();
  ASSERT_EQ(c.events.size(), 5u);
  for (int k = 0; k < 5; ++k) {
    const blvd_gnss_fix& g = c.events[static_cast<size_t>(k)].gnss;
    EXPECT_NEAR(g.lat, lats[k], 1e-7) << k;
    EXPECT_NEAR(g.lon, lons[k], 1e-7) << k;
    EXPECT_NEAR(g.t, kT0 + 0.2 * k, 1e-3) << k;
    EXPECT_NEAR(g.alt, 42.5, 1e-3);
    EXPECT_NEAR(g.speed_mps, 10.0, 1e-3);
    EXPECT_NEAR(g.track_deg, 211.0, 1e-3);
    EXPECT_NEAR(g.hdop, 0.9, 1e-3);
    EXPECT_NEAR(g.h_acc_m, 1.5, 1e-3);
    EXPECT_EQ(g.mode, 3);
    EXPECT_EQ(g.flags, BLVD_GNSS_HAS_TIME | BLVD_GNSS_HAS_LATLON | BLVD_GNSS_HAS_ALT | BLVD_GNSS_HAS_SPEED |
                           BLVD_GNSS_HAS_TRACK | BLVD_GNSS_HAS_HDOP | BLVD_GNSS_HAS_HACC);
  }
}

// A live session as a host feeds it: fixes with accuracy, then an outage (no
// fix: mode 1, time only), fixes without an accuracy value, and midnight
// (the recording's date changes; the no-fix epochs carry no trusted date).
// Replayed, every fix comes back once, at its time, with its mode, flags and
// accuracy. Before the Recorder kept its sentence cycle (GSA and GST in every
// epoch), the outage epochs ended at GSA, the decoder took GSA for the cycle's
// end and gave the first fix after the outage twice (early, without its GST,
// then completed).
TEST(Replay, RecordedOutageAndMidnightReplayEachFixOnce) {
  const double midnight = 1717286400.0;  // 2024-06-02T00:00:00Z
  std::vector<blvd_gnss_fix> live;
  for (int k = 0; k < 24; ++k) {
    const double t = midnight - 12 + k;
    blvd_gnss_fix f = makeFix(t, 43.7353 + 1e-5 * k, 7.4172 + 1e-5 * k);
    if (k >= 6 && k < 14) {  // outage across midnight
      f = blvd_gnss_fix{};
      f.struct_size = sizeof f;
      f.t = t;
      f.mode = BLVD_GNSS_MODE_NO_FIX;
      f.flags = BLVD_GNSS_HAS_TIME;
    } else if (k < 18) {  // with an accuracy (not a multiple of a millimetre times sqrt 2)
      f.h_acc_m = 1.7f + 0.01f * static_cast<float>(k);
      f.flags |= BLVD_GNSS_HAS_HACC;
    }
    live.push_back(f);
  }
  std::ostringstream out;
  Recorder rec;
  rec.attachNmea(out);
  for (const blvd_gnss_fix& f : live) ASSERT_TRUE(rec.record(f));
  std::istringstream in(out.str());
  ReplayDesc d;
  d.nmea_stream = &in;
  d.strict = true;
  const std::vector<Event> ev = replayAll(d);
  ASSERT_EQ(ev.size(), live.size()) << out.str();
  for (size_t k = 0; k < live.size(); ++k) {
    const blvd_gnss_fix &a = live[k], &b = ev[k].gnss;
    EXPECT_EQ(b.t, a.t) << k;
    EXPECT_EQ(b.mode, a.mode) << k;
    EXPECT_EQ(b.flags, a.flags) << k;
    if (!(a.flags & BLVD_GNSS_HAS_LATLON)) continue;
    EXPECT_NEAR(b.lat, a.lat, 1e-8) << k;
    EXPECT_NEAR(b.lon, a.lon, 1e-8) << k;
    if (a.flags & BLVD_GNSS_HAS_HACC) {
      EXPECT_EQ(b.h_acc_m, a.h_acc_m) << k;
    }
  }
  // The recording keeps one cycle: RMC, GGA, GSA, GST for every fix.
  std::istringstream lines(out.str());
  size_t n = 0;
  const char* const cycle[] = {"$GPRMC,", "$GPGGA,", "$GPGSA,", "$GPGST,"};
  for (std::string l; std::getline(lines, l); ++n) EXPECT_EQ(l.rfind(cycle[n % 4], 0), 0u) << "line " << n + 1 << ": " << l;
  EXPECT_EQ(n, 4 * live.size());
}

TEST(Replay, RealTimeWithSpeedFactor) {
  // 5 s of fixes and wheel speeds at 50x: about 0.1 s of wall time.
  std::istringstream nmea(nmeaTrace(kT0, 6));
  std::istringstream can(wheelTrace(0.1, 0.1, 49, 36.0));
  ReplayDesc d;
  d.nmea_stream = &nmea;
  d.candump_stream = &can;
  d.dbc_path = kToyotaDbc;
  d.has_offset = true;
  d.offset_s = kT0;
  d.pace = Pace::RealTime;
  d.speed = 50;
  const auto w0 = std::chrono::steady_clock::now();
  const std::vector<Event> ev = replayAll(d);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
  ASSERT_EQ(ev.size(), 55u);
  const double span = ev.back().t - ev.front().t;
  EXPECT_NEAR(span, 5.0, 1e-6);
  EXPECT_GE(wall, span / 50 * 0.95);
  EXPECT_LT(wall, span / 50 + 1.0);
}

TEST(Replay, Deterministic) {
  auto once = [] {
    std::istringstream nmea(nmeaTrace(kT0, 8));
    std::istringstream can(wheelTrace(7.0, 0.3, 25, 50.0));
    ReplayDesc d;
    d.nmea_stream = &nmea;
    d.candump_stream = &can;
    d.dbc_path = kToyotaDbc;
    return dump(replayAll(d));
  };
  const std::string a = once(), b = once();
  EXPECT_FALSE(a.empty());
  EXPECT_EQ(a, b);
  ReplayDesc d;
  d.nmea_path = std::string(BLVD_TEST_DATA_DIR) + "/nmea/ublox-zed-f9p-nmea.log";
  EXPECT_EQ(dump(replayAll(d)), dump(replayAll(d)));
}

TEST(Replay, ErrorsNameFileAndLine) {
  ReplayDesc d;
  std::string err;
  Replayer r;
  EXPECT_EQ(r.open(d, err), BLVD_ERR_INVALID_ARG);
  d.nmea_path = "/nonexistent/x.nmea";
  EXPECT_EQ(r.open(d, err), BLVD_ERR_IO);
  EXPECT_NE(err.find("/nonexistent/x.nmea"), std::string::npos) << err;

  std::istringstream can(wheelTrace(1.0, 1.0, 2, 10.0) + "(3.000000) can0 ZZZ#00\n");
  ReplayDesc c;
  c.candump_path = "bad.log";
  c.candump_stream = &can;
  c.dbc_path = kToyotaDbc;
  c.strict = true;
  ASSERT_EQ(r.open(c, err), BLVD_OK) << err;
  Capture cap;
  EXPECT_NE(r.run(cap, err), BLVD_OK);
  EXPECT_NE(err.find("bad.log:3"), std::string::npos) << err;
  EXPECT_EQ(cap.events.size(), 2u);
}

}  // namespace
}  // namespace blvd::replay
