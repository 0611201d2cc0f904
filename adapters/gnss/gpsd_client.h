// A client for gpsd's JSON protocol: connect over TCP (127.0.0.1:2947 by
// default), send ?WATCH={"enable":true,"json":true}; and turn the TPV reports
// into the same Fix the NMEA parser produces.
//
//   blvd::gnss::GpsdClient gpsd;
//   std::string err;
//   if (!gpsd.open({}, &err)) { ... }
//   struct : blvd::gnss::GpsdClient::Handler { void onFix(const Fix& f) override { ... } } h;
//   while (gpsd.poll(h, 1000) != ReadStatus::End) {}
//
// Mapping of a TPV: mode, time, lat, lon, altMSL (else alt), speed, track,
// geoidSep, status. gpsd puts error estimates of its own scale into TPV
// (eph, epx, ...), so those are not used; the receiver's 1-sigma errors come
// from gpsd's GST report of the same time (what GST sentences carry on the
// NMEA path), and HDOP/PDOP/VDOP and satellites used from the latest SKY.
//
// Contract: one thread per instance; nothing throws; JSON is parsed with
// nlohmann::json, so unlike the NMEA path this allocates per report.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "gnss/fix.h"
#include "gnss/source.h"

namespace blvd::gnss {

// Parses one gpsd TPV object. Returns false if the line is not a TPV (or not
// JSON), with the reason in *err when given.
bool parseGpsdTpv(std::string_view json, Fix* out, std::string* err);

class GpsdClient {
 public:
  struct Options {
    std::string host = "127.0.0.1";
    uint16_t port = 2947;
    int timeout_ms = 3000;  // connect and the ?WATCH write
    std::string device;     // watch only this device path; empty: all
  };

  class Handler {
   public:
    virtual void onFix(const Fix& f) = 0;
    // Any report, including TPV, as the raw JSON line; default: ignore.
    virtual void onReport(std::string_view /*cls*/, std::string_view /*json*/) {}
    // A line that could not be used (bad JSON, gpsd ERROR report).
    virtual void onError(const std::string& /*message*/) {}

   protected:
    ~Handler() = default;
  };

  // Connects and sends the WATCH command.
  bool open(const Options& opt, std::string* err);
  // Waits up to timeout_ms for data and handles every complete line.
  // End: gpsd closed the connection; Error: see error().
  ReadStatus poll(Handler& h, int timeout_ms);
  // What poll does with the bytes it reads: whole lines are handled, a partial
  // one waits for the rest (a recorded gpsd session, a fuzzer's input).
  void consume(std::string_view bytes, Handler& h);
  void close() { src_.close(); }
  bool isOpen() const { return src_.isOpen(); }
  const std::string& error() const { return src_.error(); }
  // gpsd's VERSION report, once received ("3.22").
  const std::string& version() const { return version_; }

 private:
  void handleLine(std::string_view line, Handler& h);

  TcpSource src_;
  std::string buf_;
  std::string version_;
  // Latest SKY and GST, merged into the TPVs that follow.
  bool have_sky_ = false;
  double hdop_ = 0, pdop_ = 0, vdop_ = 0;
  int used_ = -1;
  bool have_gst_ = false;
  double gst_time_ = 0, gst_lat_ = 0, gst_lon_ = 0, gst_alt_ = 0;
};

}  // namespace blvd::gnss
