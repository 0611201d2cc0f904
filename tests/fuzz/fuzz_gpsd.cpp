// Fuzz target for the gpsd JSON client (adapters/gnss GpsdClient: line
// framing, nlohmann::json, the TPV/SKY/GST merge). Any byte stream from a
// socket must give fixes and errors, never a crash or undefined behaviour; a
// fix carries only values the tracker can take; and the stream's chunking must
// not matter: the bytes fed whole or split in two give the same fixes and errors.
//
// Seeds: set BLVD_FUZZ_SEED_DIR and the target writes a gpsd session there
// (VERSION, DEVICES, WATCH, SKY, GST, TPV); CTest adds gpsd's decodes of the
// NMEA logs (tests/data/nmea/*.chk: TPV lines among the sentences).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "gnss/gpsd_client.h"

namespace {

using namespace blvd::gnss;

struct Record final : GpsdClient::Handler {
  std::string trace;
  void onFix(const Fix& f) override {
    check(f);
    char line[512];
    formatTpvJson(f, line, sizeof line);
    trace += line;
    char extra[64];
    std::snprintf(extra, sizeof extra, " flags=%x sats=%d\n", f.flags, f.sats_used);
    trace += extra;
  }
  void onError(const std::string& message) override {
    if (message.empty()) std::abort();  // every problem says why
    trace += message;
    trace += '\n';
  }
  static void check(const Fix& f) {
    if (f.flags & kFixHasLatLon) {
      if (!(std::fabs(f.lat) <= 90.0) || !(std::fabs(f.lon) <= 180.0)) std::abort();
    }
    if ((f.flags & kFixHasTime) && !std::isfinite(f.t_unix)) std::abort();
    if ((f.flags & kFixHasSpeed) && !std::isfinite(f.speed_mps)) std::abort();
    if ((f.flags & kFixHasTrack) && !std::isfinite(f.track_deg)) std::abort();
    if ((f.flags & kFixHasAlt) && !std::isfinite(f.alt)) std::abort();
    if ((f.flags & kFixHasHAcc) && !(f.h_acc_m >= 0)) std::abort();
    if ((f.flags & kFixHasHdop) && !(f.hdop >= 0)) std::abort();
  }
};

std::string run(std::string_view bytes, size_t split) {
  GpsdClient client;
  Record r;
  client.consume(bytes.substr(0, split), r);
  client.consume(bytes.substr(split), r);
  return r.trace;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  const char* dir = std::getenv("BLVD_FUZZ_SEED_DIR");
  if (!dir || !*dir) return 0;
  std::filesystem::create_directories(dir);
  std::ofstream f(std::filesystem::path(dir) / "session.json", std::ios::binary | std::ios::trunc);
  f << R"({"class":"VERSION","release":"3.22","rev":"3.22","proto_major":3,"proto_minor":14})" "\n"
    << R"({"class":"DEVICES","devices":[{"class":"DEVICE","path":"/dev/ttyACM0","driver":"u-blox","activated":"2024-01-01T00:00:00.000Z","native":1,"bps":9600}]})" "\n"
    << R"({"class":"WATCH","enable":true,"json":true,"nmea":false,"raw":0,"scaled":false,"timing":false,"split24":false,"pps":false})" "\n"
    << R"({"class":"SKY","device":"/dev/ttyACM0","xdop":0.54,"ydop":0.77,"vdop":1.34,"tdop":1.02,"hdop":0.94,"gdop":1.93,"pdop":1.64,"nSat":12,"uSat":9})" "\n"
    << R"({"class":"GST","device":"/dev/ttyACM0","time":"2024-01-01T12:00:01.000Z","rms":2.1,"major":3.0,"minor":1.5,"orient":20.0,"lat":1.9,"lon":1.4,"alt":3.3})" "\n"
    << R"({"class":"TPV","device":"/dev/ttyACM0","status":2,"mode":3,"time":"2024-01-01T12:00:01.000Z","ept":0.005,"lat":43.738179,"lon":7.419346,"altHAE":98.1,"altMSL":50.0,"alt":50.0,"epx":2.1,"epy":2.7,"epv":6.1,"track":304.1,"magtrack":305.0,"speed":8.4,"climb":0.1,"eps":5.4,"epc":12.2,"geoidSep":48.1})" "\n"
    << R"({"class":"TPV","mode":2,"time":"2024-01-01T12:00:02Z","lat":-90,"lon":180,"speed":0})" "\n"
    << R"({"class":"ERROR","message":"Unrecognized request 'x'"})" "\n"
    << "{\"class\":\"TPV\",\"mode\":1}\r\n";
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const std::string whole = run(bytes, size);
  const size_t split = size ? data[0] * 131u % (size + 1) : 0;
  if (run(bytes, split) != whole) std::abort();
  return 0;
}
