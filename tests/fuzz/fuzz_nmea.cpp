// Fuzz target for the NMEA 0183 stream parser (adapters/gnss: SentenceReader,
// decodeSentence, FixAssembler through NmeaDecoder). Any byte stream must
// give fixes and diagnostics, never a crash, a leak or undefined behaviour;
// and streaming must not matter: the same bytes fed whole, split in two, or
// (for short inputs) byte by byte give exactly the same fixes and messages.
//
// Seeds: set BLVD_FUZZ_SEED_DIR and the target writes a few streams of its
// own there before running (a clean multi-sentence cycle, every supported
// sentence type, broken framing); CTest adds every tests/data/nmea/*.log.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "gnss/nmea.h"

namespace {

using namespace blvd::gnss;

struct Record final : NmeaDecoder::Handler {
  bool keep = true;   // record the trace (only needed when runs are compared)
  std::string trace;  // everything emitted, in order, as text
  void onFix(const Fix& f) override {
    check(f);
    if (!keep) return;
    char line[512];
    formatTpvJson(f, line, sizeof line);
    trace += line;
    char extra[96];
    std::snprintf(extra, sizeof extra, " flags=%x sats=%d status=%d\n", f.flags, f.sats_used, f.status);
    trace += extra;
  }
  void onDiagnostic(const NmeaDiagnostic& d) override {
    if (d.code == NmeaError::None || d.message[0] == '\0' || d.line == 0) std::abort();  // every problem says why, where
    if (!keep) return;
    trace += d.message;
    trace += '\n';
  }
  static void check(const Fix& f) {
    if (f.mode < kModeUnknown || f.mode > kMode3D) std::abort();
    if (f.flags & kFixHasLatLon) {
      if (!(std::fabs(f.lat) <= 90.0) || !(std::fabs(f.lon) <= 180.0)) std::abort();
      if (f.mode < kMode2D) std::abort();  // a position only comes with a fix
    }
    if ((f.flags & kFixHasTime) && !std::isfinite(f.t_unix)) std::abort();
    if ((f.flags & kFixHasSpeed) && !std::isfinite(f.speed_mps)) std::abort();
    if ((f.flags & kFixHasTrack) && !std::isfinite(f.track_deg)) std::abort();
    if ((f.flags & kFixHasAlt) && !std::isfinite(f.alt)) std::abort();
  }
};

std::string run(const uint8_t* data, size_t size, size_t split, bool bytewise, bool keep = true) {
  NmeaDecoder dec;
  Record r;
  r.keep = keep;
  if (bytewise) {
    for (size_t i = 0; i < size; ++i) dec.feed(data + i, 1, r);
  } else {
    dec.feed(data, split, r);
    dec.feed(data + split, size - split, r);
  }
  dec.finish(r);
  return r.trace;
}

std::string withSum(const std::string& body) {
  unsigned sum = 0;
  for (size_t i = 1; i < body.size(); ++i) sum ^= static_cast<unsigned char>(body[i]);
  char tail[8];
  std::snprintf(tail, sizeof tail, "*%02X\r\n", sum);
  return body + tail;
}

void writeSeed(const std::filesystem::path& dir, const char* name, const std::string& bytes) {
  std::ofstream f(dir / name, std::ios::binary | std::ios::trunc);
  f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  const char* dir = std::getenv("BLVD_FUZZ_SEED_DIR");
  if (!dir || !*dir) return 0;
  std::filesystem::create_directories(dir);
  std::string cycle;
  for (int s = 0; s < 3; ++s) {
    char t[16];
    std::snprintf(t, sizeof t, "1200%02d.00", s);
    cycle += withSum(std::string("$GNRMC,") + t + ",A,4807.038,N,01131.000,E,1.0,10.0,010120,,,A,V");
    cycle += withSum("$GNVTG,10.0,T,,M,1.0,N,1.9,K,A");
    cycle += withSum(std::string("$GNGGA,") + t + ",4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,");
    cycle += withSum("$GNGSA,A,3,04,05,,09,12,,,24,,,,,2.5,1.3,2.1,1");
    cycle += withSum(std::string("$GNGST,") + t + ",0.006,0.023,0.020,273.6,3.0,4.0,5.5");
    cycle += withSum(std::string("$GNGLL,4807.038,N,01131.000,E,") + t + ",A,A");
    cycle += withSum(std::string("$GNZDA,") + t + ",01,01,2020,00,00");
    cycle += withSum("$GNHDT,274.07,T") + withSum("$GNTHS,274.07,A");
    cycle += withSum(std::string("$GNGNS,") + t + ",4807.038,N,01131.000,E,AAN,08,0.9,545.4,46.9,,,S");
  }
  writeSeed(dir, "seed_cycle.nmea", cycle);
  writeSeed(dir, "seed_broken.nmea",
            "# comment\r\n$GPGGA,1235\r\n$GPRMC,120000,A,4807.038,N*00\r\ngarbage\x01\x02\r\n$GPGSA,A,1,,,*\r\n" +
                withSum("$GPRMC,120000,A,48x7.038,N,01131.000,E,1.0,10.0,010120,,") + "$GPVTG,,T,,M,2C\r\n" +
                std::string(300, 'x') + "$GPGSA,A,3" + withSum("$GPGGA,235959,4807.038,N,01131.000,E,1,08,0.9,,M,,M,,") +
                withSum("$GPGGA,000000,4807.038,S,01131.000,W,1,08,0.9,-5,M,,M,,"));
  writeSeed(dir, "seed_empty.nmea", "");
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string whole = run(data, size, size, false, /*keep=*/size <= 8192);
  // The streaming checks on inputs of fuzzer size (the CTest run also feeds
  // every truncation of 60 kB logs, where one pass each is plenty). Split
  // somewhere the input itself chooses, so the fuzzer explores it.
  if (size <= 8192) {
    const size_t split = size ? data[0] * 131u % (size + 1) : 0;
    if (run(data, size, split, false) != whole) std::abort();
  }
  if (size <= 1024 && run(data, size, 0, true) != whole) std::abort();
  return 0;
}
