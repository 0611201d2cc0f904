// sim_feed: a vehicle simulator for blvd. It drives a seeded route
// through a package's street graph and writes what the car's devices would:
// NMEA 0183 (RMC+GGA+GST) to a file, a pty or TCP; CAN frames encoded with a
// vehicle DBC (Toyota by default) to a candump file or a SocketCAN interface;
// and the ground truth (CSV or JSON with the cell sequence). See README.md.
#include <CLI/CLI.hpp>
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <pty.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <thread>

#include "can/candump.h"
#include "can/socketcan.h"
#include "common/data_dir.h"
#include "gnss/fix.h"
#include "sim/sim_feed.h"

namespace {

using namespace blvd;

struct Options {
  std::string package, dbc, vehicle = "toyota", nmea_out, can_out, truth_out, start = "2026-01-01T12:00:00Z";
  sim::FeedDesc feed;
  double speed = 1;      // real-time factor for paced outputs
  bool realtime = false;
  std::string iface = "can0";
};

[[noreturn]] void die(const std::string& msg) {
  std::fprintf(stderr, "sim_feed: %s\n", msg.c_str());
  std::exit(1);
}

bool endsWith(const std::string& s, const char* suffix) {
  const size_t n = std::strlen(suffix);
  return s.size() >= n && s.compare(s.size() - n, n, suffix) == 0;
}

void writeFile(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  f << text;
  if (!f) die(path + ": cannot write");
}

// A paced byte sink for NMEA: a pty master or a TCP client socket.
int openNmeaStream(const std::string& spec) {
  if (spec == "pty") {
    int master = -1, slave = -1;
    char name[256] = {};
    if (openpty(&master, &slave, name, nullptr, nullptr) != 0) die(std::string("openpty: ") + std::strerror(errno));
    std::fprintf(stderr, "sim_feed: NMEA on %s (open it like a serial GNSS receiver)\n", name);
    // The slave stays open here so that writes do not fail before a reader opens it.
    return master;
  }
  const int port = std::atoi(spec.c_str() + 4);  // "tcp:PORT"
  if (port <= 0 || port > 65535) die("--nmea " + spec + ": expected tcp:PORT with PORT in 1..65535");
  const int srv = ::socket(AF_INET, SOCK_STREAM, 0);
  const int one = 1;
  ::setsockopt(srv, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::bind(srv, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || ::listen(srv, 1) != 0)
    die("--nmea " + spec + ": " + std::strerror(errno));
  std::fprintf(stderr, "sim_feed: NMEA on tcp://127.0.0.1:%d, waiting for a client\n", port);
  const int c = ::accept(srv, nullptr, nullptr);
  ::close(srv);
  if (c < 0) die(std::string("accept: ") + std::strerror(errno));
  return c;
}

bool writeAll(int fd, const char* p, size_t n) {
  while (n) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    p += w;
    n -= static_cast<size_t>(w);
  }
  return true;
}

// Streams both outputs merged by time, sleeping so that they keep the drive's pace.
void runPaced(const Options& o, const sim::Feed& feed, int nmea_fd, can::SocketCanSource* bus) {
  const auto wall0 = std::chrono::steady_clock::now();
  const auto sleepUntil = [&](double t) {
    const double s = (t - feed.start_unix) / (o.speed > 0 ? o.speed : 1);
    std::this_thread::sleep_until(wall0 + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                              std::chrono::duration<double>(s)));
  };
  size_t e = 0, k = 0;
  std::string err;
  while (e < feed.truth.size() || k < feed.frames.size()) {
    const bool nmea_next = nmea_fd >= 0 && e < feed.truth.size() &&
                           (!bus || k >= feed.frames.size() || feed.truth[e].t <= feed.frames[k].t);
    if (nmea_next) {
      sleepUntil(feed.truth[e].t);
      const size_t b = feed.nmea_epoch_begin[e], end = e + 1 < feed.truth.size() ? feed.nmea_epoch_begin[e + 1] : feed.nmea.size();
      if (!writeAll(nmea_fd, feed.nmea.data() + b, end - b)) die("NMEA output closed");
      ++e;
    } else if (bus && k < feed.frames.size()) {
      sleepUntil(feed.frames[k].t);
      if (bus->write(feed.frames[k], err) != BLVD_OK) die("SocketCAN: " + err);
      ++k;
    } else {
      break;
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  auto& d = o.feed.drive;  // the route, vehicle model and sensor noise
  CLI::App app{"sim_feed: simulated vehicle NMEA + CAN output on a blvd package's streets"};
  app.add_option("--package", o.package, "the .blvd whose street graph is driven")->required()->check(CLI::ExistingFile);
  o.dbc = blvd::samples::defaultDbc("toyota_new_mc_pt_generated.dbc");  // $BLVD_DATA_DIR, the source tree, the installed SDK
  app.add_option("--dbc", o.dbc, "vehicle DBC (default: see samples/common/data_dir.h)")->capture_default_str();
  app.add_option("--vehicle", o.vehicle, "toyota, vw_mqb or hyundai (the DBC must match)")->capture_default_str();
  app.add_option("--seed", d.seed, "route and noise seed")->capture_default_str();
  app.add_option("--cells", d.route_cells, "cells in the route")->capture_default_str()->check(CLI::Range(2u, 100000u));
  app.add_option("--cruise", d.cruise_mps, "top speed, m/s")->capture_default_str()->check(CLI::Range(2.0, 60.0));
  app.add_option("--accel", d.accel, "acceleration, m/s^2")->capture_default_str()->check(CLI::Range(0.1, 10.0));
  app.add_option("--nmea-rate", d.gnss_rate_hz, "NMEA epochs per second")->capture_default_str()->check(CLI::Range(1.0, 10.0));
  app.add_option("--sigma", d.gnss_sigma_m, "GNSS noise per axis, metres")->capture_default_str()->check(CLI::Range(0.0, 100.0));
  app.add_option("--drop", d.drop_fraction, "share of fixes lost")->capture_default_str()->check(CLI::Range(0.0, 1.0));
  app.add_option("--outage", d.outage_s, "one outage of this many seconds (0: none)")->capture_default_str()->check(CLI::Range(0.0, 3600.0));
  app.add_option("--outage-at", d.outage_at, "its start, as a share of the drive")->capture_default_str()->check(CLI::Range(0.0, 1.0));
  app.add_option("--can-rate", d.odo_rate_hz, "CAN samples per second (each: every message of the profile)")
      ->capture_default_str()->check(CLI::Range(10.0, 100.0));
  app.add_option("--start", o.start, "UTC time of the first sample, ISO 8601")->capture_default_str();
  app.add_option("--nmea", o.nmea_out, "NMEA output: a file, 'pty', or tcp:PORT (127.0.0.1)");
  app.add_option("--can", o.can_out, "CAN output: a candump file, or socketcan:IFACE");
  app.add_option("--iface", o.iface, "interface name written in the candump file")->capture_default_str();
  app.add_option("--truth", o.truth_out, "ground truth: FILE.csv or FILE.json");
  app.add_flag("--realtime", o.realtime, "pace file outputs too (pty, TCP and SocketCAN always are)");
  app.add_option("--speed", o.speed, "real-time factor")->capture_default_str()->check(CLI::Range(0.01, 1000.0));
  CLI11_PARSE(app, argc, argv);
  if (o.nmea_out.empty() && o.can_out.empty() && o.truth_out.empty()) die("nothing to write: give --nmea, --can or --truth");

  if (!gnss::parseIso8601(o.start.c_str(), o.start.size(), &o.feed.start_unix))
    die("--start " + o.start + ": expected YYYY-MM-DDThh:mm:ss[.fff]Z");

  sim::FeedFiles files;
  files.package_path = o.package;
  files.dbc_path = o.dbc;
  if (blvd_vehicle_from_name(o.vehicle.c_str(), &files.vehicle) != BLVD_OK)
    die("--vehicle " + o.vehicle + ": expected toyota, vw_mqb or hyundai");
  sim::Feed feed;
  std::string err;
  if (sim::makeFeed(files, o.feed, feed, err) != BLVD_OK) die(err);
  std::fprintf(stderr, "sim_feed: %zu cells, %.0f m in %.1f s; %zu NMEA epochs, %zu CAN frames; outage %.1f..%.1f s\n",
               feed.route.size(), feed.distance_m, feed.duration_s, feed.truth.size(), feed.frames.size(),
               feed.outage_begin - feed.start_unix, feed.outage_end - feed.start_unix);

  if (!o.truth_out.empty()) {
    std::ofstream f(o.truth_out);
    if (endsWith(o.truth_out, ".json")) sim::writeTruthJson(feed, f);
    else sim::writeTruthCsv(feed, f);
    if (!f) die(o.truth_out + ": cannot write");
  }
  const bool nmea_stream = o.nmea_out == "pty" || o.nmea_out.rfind("tcp:", 0) == 0;
  const bool can_bus = o.can_out.rfind("socketcan:", 0) == 0;
  if (!o.nmea_out.empty() && !nmea_stream) writeFile(o.nmea_out, feed.nmea);
  if (!o.can_out.empty() && !can_bus) writeFile(o.can_out, sim::candumpText(feed, o.iface));
  if (!nmea_stream && !can_bus && !o.realtime) return 0;

  // Paced outputs.
  can::SocketCanSource bus;
  if (can_bus) {
    can::SocketCanDesc sd;
    sd.iface = o.can_out.substr(10);
    sd.no_error_frames = true;
    if (bus.open(sd, err) != BLVD_OK) die("--can " + o.can_out + ": " + err);
  }
  int fd = -1;
  if (nmea_stream) fd = openNmeaStream(o.nmea_out);
  runPaced(o, feed, fd, can_bus ? &bus : nullptr);
  if (fd >= 0) ::close(fd);
  return 0;
}
