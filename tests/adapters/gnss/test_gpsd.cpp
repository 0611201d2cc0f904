// The gpsd client against a real gpsd: the test starts Debian's gpsd on a
// pseudo-terminal (`gpsd -N -n -b -F <socket> -S <port> <pty>`), plays a
// shared NMEA log into the terminal at a brisk pace, connects GpsdClient to
// gpsd's port, and checks that the TPV reports it turns into fixes carry the
// log's positions (and times).
//
// gpsd is a test dependency (packaging/scripts/deps.sh installs the Debian
// package); without it this test fails and says so, rather than skipping.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "gnss/gpsd_client.h"
#include "gnss/nmea.h"

namespace {

using namespace blvd::gnss;
using Clock = std::chrono::steady_clock;

std::string readFile(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// An executable on PATH or in the sbin folders (gpsd lives in /usr/sbin).
std::string findProgram(const std::string& name) {
  std::vector<std::string> dirs = {"/usr/sbin", "/usr/local/sbin", "/sbin"};
  if (const char* path = std::getenv("PATH")) {
    std::stringstream ss(path);
    std::string d;
    while (std::getline(ss, d, ':'))
      if (!d.empty()) dirs.push_back(d);
  }
  for (const auto& d : dirs) {
    const std::string p = d + "/" + name;
    if (::access(p.c_str(), X_OK) == 0) return p;
  }
  return {};
}

std::string findGpsd() { return findProgram("gpsd"); }

uint16_t freeLoopbackPort() {
  const int s = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (s < 0 || ::bind(s, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) return 0;
  socklen_t len = sizeof a;
  ::getsockname(s, reinterpret_cast<sockaddr*>(&a), &len);
  ::close(s);
  return ntohs(a.sin_port);
}

// gpsd as a child process, stopped and reaped in the destructor.
struct GpsdProcess {
  pid_t pid = -1;
  bool group = false;  // pid leads a process group (gpsfake and its gpsd): signal all of it
  std::string dir, log;
  ~GpsdProcess() {
    if (pid > 0) {
      ::kill(group ? -pid : pid, SIGTERM);
      for (int i = 0; i < 50; ++i) {
        if (::waitpid(pid, nullptr, WNOHANG) == pid) {
          pid = -1;
          break;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
      if (pid > 0) {
        ::kill(group ? -pid : pid, SIGKILL);
        ::waitpid(pid, nullptr, 0);
      }
    }
    if (!dir.empty()) {
      ::unlink((dir + "/control").c_str());
      ::unlink(log.c_str());
      ::rmdir(dir.c_str());
    }
  }
  bool alive() { return pid > 0 && ::waitpid(pid, nullptr, WNOHANG) == 0; }
  std::string output() const { return readFile(log); }
};

struct Collect final : GpsdClient::Handler {
  std::vector<Fix> fixes;
  std::vector<std::string> errors;
  std::map<std::string, int> classes;
  void onFix(const Fix& f) override { fixes.push_back(f); }
  void onReport(std::string_view cls, std::string_view) override { ++classes[std::string(cls)]; }
  void onError(const std::string& m) override { errors.push_back(m); }
};

// Connects `client` to 127.0.0.1:port, retrying while the server process starts.
::testing::AssertionResult connectWhileAlive(GpsdProcess& proc, GpsdClient& client, uint16_t port,
                                             std::chrono::seconds limit) {
  GpsdClient::Options opt;
  opt.port = port;
  std::string err;
  for (auto until = Clock::now() + limit; Clock::now() < until;) {
    if (!proc.alive()) return ::testing::AssertionFailure() << "the server exited; its output:\n" << proc.output();
    if (client.open(opt, &err)) return ::testing::AssertionSuccess();
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return ::testing::AssertionFailure() << "cannot connect to 127.0.0.1:" << port << ": " << err << "\n"
                                       << proc.output();
}

// The log's fixes with a position, decoded by our parser (which tests/adapters/gnss
// checks against gpsd's own expected output for every shared log).
std::vector<Fix> logFixes(const std::string& log) {
  std::vector<Fix> reference;
  struct R final : NmeaDecoder::Handler {
    std::vector<Fix>* out;
    void onFix(const Fix& f) override {
      if (f.mode >= kMode2D) out->push_back(f);
    }
    void onDiagnostic(const NmeaDiagnostic&) override {}
  } r;
  r.out = &reference;
  NmeaDecoder d;
  d.feed(log.data(), log.size(), r);
  d.finish(r);
  return reference;
}

// Polls until `want` TPVs with a position arrived (or the time is up); returns how many did.
size_t collectPositions(GpsdClient& client, Collect& got, size_t want, std::chrono::seconds limit) {
  size_t with_position = 0;
  for (auto until = Clock::now() + limit; Clock::now() < until && with_position < want;) {
    const ReadStatus st = client.poll(got, 200);
    if (st == ReadStatus::End || st == ReadStatus::Error) break;
    with_position = 0;
    for (const Fix& f : got.fixes) with_position += (f.mode >= kMode2D && (f.flags & kFixHasLatLon)) ? 1 : 0;
  }
  return with_position;
}

// Every position gpsd reports is one of the log's, to 1e-7 degrees; returns how
// many of them also carry the time our fix of that position has.
size_t checkPositionsInLog(const std::vector<Fix>& fixes, const std::vector<Fix>& reference) {
  size_t timed_same = 0;
  for (const Fix& f : fixes) {
    if (f.mode < kMode2D || !(f.flags & kFixHasLatLon)) continue;
    bool found = false;
    for (const Fix& r : reference) {
      if (std::fabs(r.lat - f.lat) <= 1e-7 && std::fabs(r.lon - f.lon) <= 1e-7) {
        found = true;
        if ((f.flags & kFixHasTime) && (r.flags & kFixHasTime) && std::fabs(r.t_unix - f.t_unix) < 0.0005)
          ++timed_same;
        break;
      }
    }
    char where[96];
    std::snprintf(where, sizeof where, "%.9f,%.9f", f.lat, f.lon);
    EXPECT_TRUE(found) << "gpsd reported a position that is not in the log: " << where;
  }
  return timed_same;
}

TEST(GpsdClient, ParsesTpv) {
  Fix f;
  ASSERT_TRUE(parseGpsdTpv(
      R"({"class":"TPV","device":"/dev/pts/1","mode":3,"time":"2020-03-18T13:28:19.600Z","ept":0.005,)"
      R"("lat":41.57496591,"lon":-93.750571901,"altHAE":246.719,"altMSL":278.161,"alt":278.161,"track":124.888,)"
      R"("speed":0.076,"geoidSep":-31.442,"status":2})",
      &f, nullptr));
  EXPECT_EQ(f.mode, kMode3D);
  EXPECT_EQ(f.status, kStatusDgps);
  char t[40];
  formatIso8601(f.t_unix, t, sizeof t);
  EXPECT_STREQ(t, "2020-03-18T13:28:19.600Z");
  EXPECT_DOUBLE_EQ(f.lat, 41.57496591);
  EXPECT_DOUBLE_EQ(f.lon, -93.750571901);
  EXPECT_DOUBLE_EQ(f.alt, 278.161);
  EXPECT_NEAR(f.speed_mps, 0.076, 1e-6);
  EXPECT_NEAR(f.track_deg, 124.888, 1e-4);
  EXPECT_EQ(f.flags, kFixHasTime | kFixHasLatLon | kFixHasAlt | kFixHasSpeed | kFixHasTrack | kFixHasGeoidSep);

  ASSERT_TRUE(parseGpsdTpv(R"({"class":"TPV","mode":1})", &f, nullptr));
  EXPECT_EQ(f.mode, kModeNoFix);
  EXPECT_EQ(f.flags, 0u);
  std::string err;
  EXPECT_FALSE(parseGpsdTpv(R"({"class":"SKY","hdop":1.0})", &f, &err));
  EXPECT_FALSE(parseGpsdTpv("{not json", &f, &err));
  EXPECT_FALSE(err.empty());
}

TEST(GpsdClient, ReceivesTheLogsPositionsFromARealGpsd) {
  const std::string gpsd = findGpsd();
  ASSERT_FALSE(gpsd.empty()) << "gpsd is not installed: this test needs Debian's 'gpsd' package "
                                "(apt-get install gpsd; packaging/scripts/deps.sh installs it)";

  const std::string log_path = std::string(BLVD_TEST_DATA_DIR) + "/nmea/nmea-rtk.log";
  const std::string log = readFile(log_path);
  ASSERT_FALSE(log.empty());

  const std::vector<Fix> reference = logFixes(log);
  ASSERT_GT(reference.size(), 100u);

  // The receiver: a pseudo-terminal.
  const int master = ::posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK);
  ASSERT_GE(master, 0);
  ASSERT_EQ(::grantpt(master), 0);
  ASSERT_EQ(::unlockpt(master), 0);
  const std::string slave = ::ptsname(master);
  // gpsd drops root privileges after start-up; let it reopen the device.
  ::chmod(slave.c_str(), 0666);

  GpsdProcess proc;
  char dir_template[] = "/tmp/blvd-gpsd-XXXXXX";
  ASSERT_NE(::mkdtemp(dir_template), nullptr);
  proc.dir = dir_template;
  ::chmod(proc.dir.c_str(), 0777);
  proc.log = proc.dir + "/gpsd.log";
  const uint16_t port = freeLoopbackPort();
  ASSERT_NE(port, 0);
  const std::string port_s = std::to_string(port), control = proc.dir + "/control";

  proc.pid = ::fork();
  ASSERT_GE(proc.pid, 0);
  if (proc.pid == 0) {
    const int out = ::open(proc.log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (out >= 0) {
      ::dup2(out, 1);
      ::dup2(out, 2);
    }
    // -N foreground, -n open the device now, -b never write to it,
    // -F control socket, -S port (gpsd listens on loopback only by default).
    ::execl(gpsd.c_str(), "gpsd", "-N", "-n", "-b", "-D", "1", "-F", control.c_str(), "-S", port_s.c_str(),
            slave.c_str(), static_cast<char*>(nullptr));
    std::_Exit(127);
  }

  // Wait for gpsd to listen.
  GpsdClient client;
  ASSERT_TRUE(connectWhileAlive(proc, client, port, std::chrono::seconds(10)));

  Collect got;
  // Let gpsd answer the WATCH before the data flows.
  for (auto until = Clock::now() + std::chrono::seconds(3); Clock::now() < until && !got.classes.count("WATCH");)
    client.poll(got, 100);

  // Play the log, line by line at ~500 lines/s, up to three times, while
  // throwing away anything gpsd might write to the device.
  std::atomic<bool> stop{false};
  std::thread feeder([&] {
    for (int pass = 0; pass < 3 && !stop; ++pass) {
      size_t at = 0;
      while (at < log.size() && !stop) {
        size_t nl = log.find('\n', at);
        nl = nl == std::string::npos ? log.size() : nl + 1;
        size_t off = at;
        while (off < nl && !stop) {
          const ssize_t w = ::write(master, log.data() + off, nl - off);
          if (w > 0)
            off += static_cast<size_t>(w);
          else
            std::this_thread::sleep_for(std::chrono::milliseconds(1));
        }
        at = nl;
        char sink[256];
        while (::read(master, sink, sizeof sink) > 0) {
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
      }
    }
  });

  const size_t with_position = collectPositions(client, got, 40, std::chrono::seconds(30));
  stop = true;
  feeder.join();
  ::close(master);

  EXPECT_FALSE(client.version().empty()) << "no VERSION report from gpsd";
  ASSERT_GE(with_position, 40u) << "gpsd sent " << got.fixes.size() << " TPVs, " << with_position
                                << " with a position; gpsd's output:\n"
                                << proc.output();

  const size_t timed_same = checkPositionsInLog(got.fixes, reference);
  std::printf("[gpsd] %s: %zu TPVs, %zu with a position (all in the log), %zu with the same time as ours\n",
              client.version().c_str(), got.fixes.size(), with_position, timed_same);
  // The time too: gpsd stamps a position with its cycle's time, as we do,
  // except at the cycle it joined mid-way (38 of 40 measured).
  EXPECT_GE(timed_same + 4, with_position) << "positions whose time differs from ours";
}

// The setup a host uses: gpsd fed by gpsfake (Debian's gpsd-clients), which starts
// its own gpsd on a pty, waits for a client and plays the log once.
TEST(GpsdClient, ReceivesTheLogsPositionsThroughGpsfake) {
  const std::string gpsd = findGpsd();
  ASSERT_FALSE(gpsd.empty()) << "gpsd is not installed (apt-get install gpsd; packaging/scripts/deps.sh)";
  const std::string gpsfake = findProgram("gpsfake");
  ASSERT_FALSE(gpsfake.empty()) << "gpsfake is not installed: it is in Debian's 'gpsd-clients' package "
                                   "(apt-get install gpsd-clients; packaging/scripts/deps.sh installs it)";
  const std::string log_path = std::string(BLVD_TEST_DATA_DIR) + "/nmea/nmea-rtk.log";
  const std::vector<Fix> reference = logFixes(readFile(log_path));
  ASSERT_GT(reference.size(), 100u);

  GpsdProcess proc;
  char dir_template[] = "/tmp/blvd-gpsfake-XXXXXX";
  ASSERT_NE(::mkdtemp(dir_template), nullptr);
  proc.dir = dir_template;
  proc.log = proc.dir + "/gpsfake.log";
  const uint16_t port = freeLoopbackPort();
  ASSERT_NE(port, 0);
  const std::string port_s = std::to_string(port);
  // gpsfake runs the gpsd it finds on PATH.
  const std::string path = gpsd.substr(0, gpsd.rfind('/')) + ":" + (std::getenv("PATH") ? std::getenv("PATH") : "/usr/bin");
  proc.pid = ::fork();
  ASSERT_GE(proc.pid, 0);
  if (proc.pid == 0) {
    const int out = ::open(proc.log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (out >= 0) {
      ::dup2(out, 1);
      ::dup2(out, 2);
    }
    ::setpgid(0, 0);  // gpsfake's gpsd child goes down with it (GpsdProcess kills the group)
    ::setenv("PATH", path.c_str(), 1);
    // -1 play the log once, -c seconds between sentences, -P gpsd's port.
    ::execl(gpsfake.c_str(), "gpsfake", "-1", "-c", "0.01", "-P", port_s.c_str(), log_path.c_str(),
            static_cast<char*>(nullptr));
    std::_Exit(127);
  }
  proc.group = true;

  GpsdClient client;
  ASSERT_TRUE(connectWhileAlive(proc, client, port, std::chrono::seconds(15)));
  Collect got;
  const size_t with_position = collectPositions(client, got, 60, std::chrono::seconds(40));
  EXPECT_FALSE(client.version().empty()) << "no VERSION report from gpsd";
  ASSERT_GE(with_position, 60u) << "gpsd sent " << got.fixes.size() << " TPVs, " << with_position
                                << " with a position; gpsfake's output:\n"
                                << proc.output();
  // gpsd's first reports, before it has locked onto the log's cycle, may carry
  // another epoch's time; most must agree.
  EXPECT_GE(checkPositionsInLog(got.fixes, reference), 40u);
}

}  // namespace
