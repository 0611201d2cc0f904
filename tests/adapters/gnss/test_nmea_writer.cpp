// NMEA writer (nmea_writer.h): what it writes, the parser reads back - every
// field to the written resolution, no-fix epochs as no fix, one fix per epoch
// (the cycle is RMC GGA GST with or without a fix), times across midnight and
// year ends, and hemispheres.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "gnss/nmea.h"
#include "gnss/nmea_writer.h"

namespace blvd::gnss {
namespace {

struct Collect final : NmeaDecoder::Handler {
  std::vector<Fix> fixes;
  std::vector<NmeaDiagnostic> diags;
  void onFix(const Fix& f) override { fixes.push_back(f); }
  void onDiagnostic(const NmeaDiagnostic& d) override { diags.push_back(d); }
};

Fix fixAt(double t, double lat, double lon) {
  Fix f = Fix::empty();
  f.t_unix = t;
  f.lat = lat;
  f.lon = lon;
  f.alt = 12.5;
  f.speed_mps = 13.2f;
  f.track_deg = 271.25f;
  f.hdop = 0.9f;
  f.h_acc_m = 7.07f;
  f.mode = kMode3D;
  f.flags = kFixHasTime | kFixHasLatLon | kFixHasAlt | kFixHasSpeed | kFixHasTrack | kFixHasHdop | kFixHasHAcc;
  return f;
}

TEST(NmeaWriter, ChecksummedSentences) {
  std::string out;
  appendSentence("GPGGA,,,,,,0,00,,,M,,M,,", out);
  EXPECT_EQ(out, "$GPGGA,,,,,,0,00,,,M,,M,,*66\r\n");
}

TEST(NmeaWriter, ParsesBackEveryField) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> lat(-89.9, 89.9), lon(-179.9, 179.9);
  std::vector<Fix> written;
  std::string text;
  const NmeaWriterOptions opt;
  // 2025-12-31T23:59:58Z: the epochs cross midnight and the year.
  for (int k = 0; k < 200; ++k) {
    Fix f = fixAt(1767225598.0 + 0.5 * k, lat(rng), lon(rng));
    if (k % 7 == 3) {  // a lost fix
      f.flags = kFixHasTime;
      f.mode = kModeNoFix;
    }
    written.push_back(f);
    appendEpoch(f, opt, text);
  }
  NmeaDecoder dec(NmeaDecoder::Options{});
  Collect c;
  dec.feed(text.data(), text.size(), c);
  dec.finish(c);
  EXPECT_TRUE(c.diags.empty()) << c.diags.front().message;
  ASSERT_EQ(c.fixes.size(), written.size());
  for (size_t i = 0; i < written.size(); ++i) {
    const Fix& w = written[i];
    const Fix& r = c.fixes[i];
    EXPECT_FALSE(r.flags & kFixUpdate) << i;
    EXPECT_NEAR(r.t_unix, w.t_unix, 1e-6) << i;
    if (w.mode == kModeNoFix) {
      EXPECT_EQ(r.mode, kModeNoFix) << i;
      EXPECT_FALSE(r.flags & kFixHasLatLon) << i;
      continue;
    }
    ASSERT_TRUE(r.flags & kFixHasLatLon) << i;
    EXPECT_NEAR(r.lat, w.lat, 1e-6 / 60 + 1e-12) << i;  // 6 decimals of a minute
    EXPECT_NEAR(r.lon, w.lon, 1e-6 / 60 + 1e-12) << i;
    EXPECT_NEAR(r.alt, w.alt, 0.005) << i;
    EXPECT_NEAR(r.speed_mps, w.speed_mps, 0.0005 * 0.514444 + 1e-4) << i;
    EXPECT_NEAR(r.track_deg, w.track_deg, 0.005) << i;
    EXPECT_NEAR(r.hdop, w.hdop, 0.05) << i;
    EXPECT_NEAR(r.h_acc_m, w.h_acc_m, 0.01) << i;
  }
}

TEST(NmeaWriter, MinutesRoundIntoDegrees) {
  // 59.9999999' rounds to 60.000000': written as the next degree, not "4360.000000".
  std::string text;
  appendEpoch(fixAt(1767268800.0, 43.0 + 59.99999999 / 60.0, -(7.0 + 59.99999999 / 60.0)), NmeaWriterOptions{}, text);
  EXPECT_NE(text.find(",4400.000000,N,00800.000000,W,"), std::string::npos) << text;
}

}  // namespace
}  // namespace blvd::gnss
