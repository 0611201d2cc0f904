// `blvd nmea decode`: NMEA 0183 in, one fix per epoch out.
//
//   blvd nmea decode LOG [--json]          a log file ("-": standard input)
//   blvd nmea decode --serial DEV [--baud N] [--count N]
//   blvd nmea decode --tcp HOST:PORT [--count N]
//
// --json prints one gpsd-style TPV object per fix per line; without it, a
// table. Problems in the input go to standard error with their line number
// and byte offset and do not stop decoding. Exit status: 0 when the input
// was read to its end (or --count fixes were printed), 1 when it could not
// be opened or read, 2 for bad arguments.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include "cli/commands.h"
#include "gnss/nmea.h"
#include "gnss/source.h"

namespace blvd::cli {
namespace {

struct DecodeArgs {
  std::string log;
  std::string serial;
  int baud = 9600;
  std::string tcp;
  bool json = false;
  long count = 0;  // 0: no limit
  bool quiet = false;
};

class Printer final : public gnss::NmeaDecoder::Handler {
 public:
  Printer(const DecodeArgs& a, const std::string& name) : args_(a), name_(name) {}

  void onFix(const gnss::Fix& f) override {
    ++fixes_;
    if (args_.json) {
      char line[512];
      gnss::formatTpvJson(f, line, sizeof line);
      std::printf("%s\n", line);
    } else {
      if (fixes_ == 1)
        std::printf("%-24s %4s %14s %15s %9s %8s %8s %5s %4s\n", "time (UTC)", "mode", "lat", "lon", "alt m",
                    "speed m/s", "track", "hdop", "sats");
      char t[40] = "-";
      if (f.flags & gnss::kFixHasTime) gnss::formatIso8601(f.t_unix, t, sizeof t);
      auto num = [](char* out, size_t cap, bool has, const char* fmt, double v) {
        if (has)
          std::snprintf(out, cap, fmt, v);
        else
          std::snprintf(out, cap, "-");
      };
      char lat[24], lon[24], alt[24], spd[24], trk[24], hdop[16];
      num(lat, sizeof lat, f.flags & gnss::kFixHasLatLon, "%.7f", f.lat);
      num(lon, sizeof lon, f.flags & gnss::kFixHasLatLon, "%.7f", f.lon);
      num(alt, sizeof alt, f.flags & gnss::kFixHasAlt, "%.1f", f.alt);
      num(spd, sizeof spd, f.flags & gnss::kFixHasSpeed, "%.3f", static_cast<double>(f.speed_mps));
      num(trk, sizeof trk, f.flags & gnss::kFixHasTrack, "%.2f", static_cast<double>(f.track_deg));
      num(hdop, sizeof hdop, f.flags & gnss::kFixHasHdop, "%.1f", static_cast<double>(f.hdop));
      static const char* kModes[] = {"?", "none", "2D", "3D"};
      std::printf("%-24s %4s %14s %15s %9s %8s %8s %5s %4d%s\n", t, kModes[f.mode & 3], lat, lon, alt, spd, trk, hdop,
                  f.sats_used, (f.flags & gnss::kFixUpdate) ? " (update)" : "");
    }
    if (args_.count > 0 && fixes_ >= static_cast<unsigned long>(args_.count)) done_ = true;
  }

  void onDiagnostic(const gnss::NmeaDiagnostic& d) override {
    ++problems_;
    if (!args_.quiet) std::fprintf(stderr, "%s: %s\n", name_.c_str(), d.message);
  }

  bool done() const { return done_; }
  unsigned long fixes() const { return fixes_; }
  unsigned long problems() const { return problems_; }

 private:
  const DecodeArgs& args_;
  std::string name_;
  unsigned long fixes_ = 0;
  unsigned long problems_ = 0;
  bool done_ = false;
};

int decode(const DecodeArgs& a) {
  const int inputs = !a.log.empty() + !a.serial.empty() + !a.tcp.empty();
  if (inputs != 1) {
    std::fprintf(stderr, "blvd nmea decode: give exactly one of LOG, --serial DEV, --tcp HOST:PORT\n");
    return 2;
  }
  std::unique_ptr<gnss::FdSource> src;
  std::string err, name;
  if (!a.log.empty()) {
    auto f = std::make_unique<gnss::FileSource>();
    if (!f->open(a.log, &err)) {
      std::fprintf(stderr, "blvd nmea decode: cannot read %s\n", err.c_str());
      return 1;
    }
    name = a.log == "-" ? "<stdin>" : a.log;
    src = std::move(f);
  } else if (!a.serial.empty()) {
    auto s = std::make_unique<gnss::SerialSource>();
    if (!s->open(a.serial, a.baud, &err)) {
      std::fprintf(stderr, "blvd nmea decode: %s\n", err.c_str());
      return 1;
    }
    name = a.serial;
    src = std::move(s);
  } else {
    const size_t colon = a.tcp.rfind(':');
    int port = 0;
    if (colon == std::string::npos || colon == 0 || (port = std::atoi(a.tcp.c_str() + colon + 1)) <= 0 || port > 65535) {
      std::fprintf(stderr, "blvd nmea decode: --tcp wants HOST:PORT, got '%s'\n", a.tcp.c_str());
      return 2;
    }
    auto t = std::make_unique<gnss::TcpSource>();
    if (!t->connect(a.tcp.substr(0, colon), static_cast<uint16_t>(port), 5000, &err)) {
      std::fprintf(stderr, "blvd nmea decode: %s\n", err.c_str());
      return 1;
    }
    name = a.tcp;
    src = std::move(t);
  }

  Printer out(a, name);
  // A log is read as fast as the disk allows, so nothing is gained by
  // emitting an epoch before the next one starts: one line per epoch. Live
  // sources keep the early emission (one cycle less latency).
  gnss::NmeaDecoder::Options opt;
  opt.assembler.early_emit = a.log.empty();
  gnss::NmeaDecoder dec(opt);
  char buf[8192];
  while (!out.done()) {
    const gnss::ReadResult r = src->read(buf, sizeof buf, -1);
    if (r.status == gnss::ReadStatus::Data) {
      dec.feed(buf, r.bytes, out);
    } else if (r.status == gnss::ReadStatus::End) {
      break;
    } else if (r.status == gnss::ReadStatus::Error) {
      dec.finish(out);
      std::fflush(stdout);
      std::fprintf(stderr, "blvd nmea decode: %s: %s\n", name.c_str(), src->error().c_str());
      return 1;
    }
  }
  if (!out.done()) dec.finish(out);
  std::fflush(stdout);
  if (!a.json && !a.quiet) {
    const auto& st = dec.readerStats();
    std::fprintf(stderr, "%s: %lu fixes from %llu sentences (%llu without checksum), %lu problems\n", name.c_str(),
                 out.fixes(), static_cast<unsigned long long>(st.sentences),
                 static_cast<unsigned long long>(st.no_checksum), out.problems());
  }
  return 0;
}

}  // namespace

void addNmea(CLI::App& app, Runner& run) {
  auto* nmea = app.add_subcommand("nmea", "decode NMEA 0183 (GNSS receiver output)");
  nmea->require_subcommand(1);
  auto args = std::make_shared<DecodeArgs>();
  auto* dec = nmea->add_subcommand("decode", "print one fix per receiver epoch (gpsd-style TPV with --json)");
  dec->add_option("log", args->log, "NMEA log file ('-' for standard input)");
  dec->add_option("--serial", args->serial, "read a serial device instead (raw mode)");
  dec->add_option("--baud", args->baud, "serial baud rate (default 9600)");
  dec->add_option("--tcp", args->tcp, "read NMEA from a TCP server, HOST:PORT");
  dec->add_option("--count", args->count, "stop after this many fixes");
  dec->add_flag("--json", args->json, "one gpsd-style TPV JSON object per fix per line");
  dec->add_flag("-q,--quiet", args->quiet, "do not report input problems");
  dec->callback([&run, args] { run = [args] { return decode(*args); }; });
}

}  // namespace blvd::cli
