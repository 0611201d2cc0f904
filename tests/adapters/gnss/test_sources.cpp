// Byte sources: a file, a serial device (a pseudo-terminal pair stands in for
// the receiver), and a TCP client against a loopback listener. Each must
// deliver the log byte for byte, so decoding through it gives exactly the
// fixes that decoding the file in memory gives.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "gnss/nmea.h"
#include "gnss/source.h"

namespace {

using namespace blvd::gnss;

std::string readFile(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}
std::string dataPath(const std::string& name) { return std::string(BLVD_TEST_DATA_DIR) + "/nmea/" + name; }

// Reads a source to its end (or until `want` bytes), with an overall deadline.
std::string drain(Source& src, size_t want, int deadline_ms) {
  std::string got;
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(deadline_ms);
  char buf[1024];
  while (got.size() < want && std::chrono::steady_clock::now() < end) {
    const ReadResult r = src.read(buf, sizeof buf, 100);
    if (r.status == ReadStatus::Data) got.append(buf, r.bytes);
    if (r.status == ReadStatus::End || r.status == ReadStatus::Error) break;
  }
  return got;
}

struct Fixes final : NmeaDecoder::Handler {
  std::vector<Fix> all;
  void onFix(const Fix& f) override { all.push_back(f); }
  void onDiagnostic(const NmeaDiagnostic&) override {}
};

std::vector<Fix> decodeBytes(const std::string& bytes) {
  NmeaDecoder d;
  Fixes out;
  d.feed(bytes.data(), bytes.size(), out);
  d.finish(out);
  return out.all;
}

void expectSameFixes(const std::vector<Fix>& a, const std::vector<Fix>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].mode, b[i].mode) << i;
    EXPECT_EQ(a[i].flags, b[i].flags) << i;
    if (a[i].flags & kFixHasLatLon) {
      EXPECT_EQ(a[i].lat, b[i].lat) << i;
      EXPECT_EQ(a[i].lon, b[i].lon) << i;
    }
  }
}

TEST(GnssSource, FileDeliversTheLogByteForByte) {
  const std::string path = dataPath("bt451.log");
  const std::string expect = readFile(path);
  FileSource f;
  std::string err;
  ASSERT_TRUE(f.open(path, &err)) << err;
  const std::string got = drain(f, SIZE_MAX, 5000);
  EXPECT_EQ(got, expect);
  char c;
  EXPECT_EQ(f.read(&c, 1, 0).status, ReadStatus::End);

  FileSource missing;
  EXPECT_FALSE(missing.open("/nonexistent/nmea.log", &err));
  EXPECT_NE(err.find("/nonexistent/nmea.log"), std::string::npos) << err;
}

// A pseudo-terminal pair: the test writes the log into the master side at
// receiver-like pace; SerialSource reads the slave side in raw mode.
TEST(GnssSource, SerialDeviceOverAPseudoTerminal) {
  const int master = ::posix_openpt(O_RDWR | O_NOCTTY);
  ASSERT_GE(master, 0) << "posix_openpt: " << std::strerror(errno);
  ASSERT_EQ(::grantpt(master), 0);
  ASSERT_EQ(::unlockpt(master), 0);
  const char* slave_name = ::ptsname(master);
  ASSERT_NE(slave_name, nullptr);
  const std::string slave = slave_name;

  SerialSource serial;
  std::string err;
  ASSERT_FALSE(serial.open(slave, 12345, &err));
  EXPECT_NE(err.find("unsupported baud rate 12345"), std::string::npos) << err;
  ASSERT_TRUE(serial.open(slave, 115200, &err)) << err;

  // Raw mode: no echo, no CR/LF translation, 8 bits, 115200.
  termios t{};
  ASSERT_EQ(::tcgetattr(serial.fd(), &t), 0);
  EXPECT_EQ(t.c_lflag & (ECHO | ICANON | ISIG), 0u);
  EXPECT_EQ(t.c_iflag & (ICRNL | INLCR | IGNCR | IXON), 0u);
  EXPECT_EQ(t.c_cflag & CSIZE, static_cast<tcflag_t>(CS8));
  EXPECT_EQ(::cfgetispeed(&t), static_cast<speed_t>(B115200));

  // Nothing written yet: a read times out.
  char c;
  EXPECT_EQ(serial.read(&c, 1, 50).status, ReadStatus::Timeout);

  const std::string log = readFile(dataPath("haicom-305N.log"));
  std::thread writer([&] {
    // Lines in bursts, like a receiver at a high baud rate.
    size_t at = 0;
    while (at < log.size()) {
      size_t n = std::min<size_t>(700, log.size() - at);
      while (n > 0) {
        const ssize_t w = ::write(master, log.data() + at, n);
        if (w > 0) {
          at += static_cast<size_t>(w);
          n -= static_cast<size_t>(w);
        } else if (w < 0 && errno != EAGAIN && errno != EINTR) {
          return;
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  });
  const std::string got = drain(serial, log.size(), 20000);
  writer.join();
  EXPECT_EQ(got.size(), log.size());
  EXPECT_EQ(got, log);
  expectSameFixes(decodeBytes(got), decodeBytes(log));

  // Raw mode also means no echo back to the "receiver".
  pollfd p{master, POLLIN, 0};
  EXPECT_EQ(::poll(&p, 1, 50), 0) << "the serial side echoed input back";

  // The receiver goes away (USB unplugged): the read reports the end, not an error.
  ::close(master);
  const ReadResult r = serial.read(&c, 1, 1000);
  EXPECT_EQ(r.status, ReadStatus::End);
  serial.close();

  // Not a terminal.
  SerialSource notty;
  EXPECT_FALSE(notty.open(dataPath("bt451.log"), 9600, &err));
  EXPECT_NE(err.find("not a terminal"), std::string::npos) << err;
}

// NMEA over TCP (as from a network receiver or `gpspipe | nc -l`): a loopback
// listener sends the log and closes; TcpSource reads it all.
TEST(GnssSource, TcpClientAgainstALoopbackListener) {
  const int listener = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  ASSERT_GE(listener, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = 0;
  ASSERT_EQ(::bind(listener, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  ASSERT_EQ(::listen(listener, 1), 0);
  socklen_t len = sizeof addr;
  ASSERT_EQ(::getsockname(listener, reinterpret_cast<sockaddr*>(&addr), &len), 0);
  const uint16_t port = ntohs(addr.sin_port);

  const std::string log = readFile(dataPath("ublox-zed-f9p-nmea.log"));
  std::thread server([&] {
    pollfd p{listener, POLLIN, 0};
    if (::poll(&p, 1, 5000) != 1) return;
    const int c = ::accept(listener, nullptr, nullptr);
    if (c < 0) return;
    size_t at = 0;
    while (at < log.size()) {
      const ssize_t w = ::send(c, log.data() + at, std::min<size_t>(1500, log.size() - at), MSG_NOSIGNAL);
      if (w <= 0) break;
      at += static_cast<size_t>(w);
    }
    ::close(c);
  });

  TcpSource tcp;
  std::string err;
  ASSERT_TRUE(tcp.connect("127.0.0.1", port, 2000, &err)) << err;
  const std::string got = drain(tcp, SIZE_MAX, 10000);
  server.join();
  ::close(listener);
  EXPECT_EQ(got, log);
  expectSameFixes(decodeBytes(got), decodeBytes(log));
  char c;
  EXPECT_EQ(tcp.read(&c, 1, 100).status, ReadStatus::End);

  // Nobody listening there any more: a clear error, no hang.
  TcpSource refused;
  EXPECT_FALSE(refused.connect("127.0.0.1", port, 2000, &err));
  EXPECT_NE(err.find("127.0.0.1:" + std::to_string(port)), std::string::npos) << err;
}

}  // namespace
