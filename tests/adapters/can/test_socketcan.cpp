// SocketCAN source: a clear error where the kernel has no AF_CAN (this build
// machine, most containers), error-frame decoding on synthesized frames, and,
// where a vcan0 exists (the qemu guest of tests/vcan), a loopback round trip,
// error frames on the bus, and the bus going down and coming back.
#include <gtest/gtest.h>

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "can/candump.h"
#include "can/socketcan.h"

namespace blvd::can {
namespace {

// Whether this kernel can open a CAN_RAW socket at all, asked directly.
int probeAfCan() {
  const int s = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (s < 0) return errno;
  ::close(s);
  return 0;
}

TEST(SocketCan, ClearErrorWithoutAfCan) {
  const int e = probeAfCan();
  if (e != EAFNOSUPPORT) GTEST_SKIP() << "this kernel has AF_CAN (probe: " << std::strerror(e) << ")";
  SocketCanSource src;
  SocketCanDesc desc;
  desc.iface = "vcan0";
  std::string err;
  EXPECT_EQ(src.open(desc, err), BLVD_ERR_UNSUPPORTED);
  EXPECT_EQ(err.rfind("AF_CAN not supported by this kernel", 0), 0u) << err;
  EXPECT_NE(err.find("modprobe can_raw"), std::string::npos) << err;
  EXPECT_FALSE(src.isOpen());
  EXPECT_EQ(src.fd(), -1);
  Frame f;
  EXPECT_EQ(src.read(f, 0, err), SocketCanSource::Result::Error);
  EXPECT_EQ(err, "SocketCAN source is not open");
  EXPECT_EQ(src.write(f, err), BLVD_ERR_MISUSE);
}

TEST(SocketCan, UnknownInterfaceWhereAfCanExists) {
  if (probeAfCan() != 0) GTEST_SKIP() << "no AF_CAN on this kernel";
  SocketCanSource src;
  SocketCanDesc desc;
  desc.iface = "blvdnone0";
  std::string err;
  EXPECT_EQ(src.open(desc, err), BLVD_ERR_NOT_FOUND);
  EXPECT_NE(err.find("no network interface named 'blvdnone0'"), std::string::npos) << err;
  desc.iface = "a_name_that_is_far_too_long";
  EXPECT_EQ(src.open(desc, err), BLVD_ERR_INVALID_ARG);
}

// On a machine with vcan0 up (ip link add dev vcan0 type vcan; ip link set up vcan0):
// a frame written is read back by a second socket, with a kernel timestamp.
TEST(SocketCan, VcanLoopbackIfPresent) {
  if (probeAfCan() != 0) GTEST_SKIP() << "no AF_CAN on this kernel";
  SocketCanSource rx, tx;
  SocketCanDesc desc;
  desc.iface = "vcan0";
  desc.filters.push_back({0x123, 0x7FF, false, false});
  std::string err;
  if (rx.open(desc, err) != BLVD_OK) GTEST_SKIP() << err;
  SocketCanDesc tdesc;
  tdesc.iface = "vcan0";
  ASSERT_EQ(tx.open(tdesc, err), BLVD_OK) << err;
  Frame f;
  std::string reason;
  ASSERT_TRUE(parseFrame("124#FF", f, reason));  // filtered out
  ASSERT_EQ(tx.write(f, err), BLVD_OK) << err;
  ASSERT_TRUE(parseFrame("123#DEADBEEF", f, reason));
  ASSERT_EQ(tx.write(f, err), BLVD_OK) << err;
  Frame got;
  ASSERT_EQ(rx.read(got, 1000, err), SocketCanSource::Result::Frame) << err;
  EXPECT_EQ(formatFrame(got), "123#DEADBEEF");
  EXPECT_EQ(got.iface, "vcan0");
  EXPECT_GT(got.t, 1.5e9);
  EXPECT_EQ(rx.read(got, 50, err), SocketCanSource::Result::Timeout);
}

// Sets vcan0 up or down (SIOCSIFFLAGS, as `ip link set vcan0 up|down`); errno on failure.
int setLink(const char* iface, bool up) {
  const int s = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (s < 0) return errno;
  ifreq ifr{};
  std::strncpy(ifr.ifr_name, iface, IFNAMSIZ - 1);
  int rc = ::ioctl(s, SIOCGIFFLAGS, &ifr);
  if (rc == 0) {
    ifr.ifr_flags = static_cast<short>(up ? (ifr.ifr_flags | IFF_UP) : (ifr.ifr_flags & ~IFF_UP));
    rc = ::ioctl(s, SIOCSIFFLAGS, &ifr);
  }
  const int e = rc == 0 ? 0 : errno;
  ::close(s);
  return e;
}

// Puts an error frame on vcan0 as a controller's driver would (a raw socket
// may send CAN_ERR_FLAG frames; the vcan echoes them to the sockets that asked
// for that class). SocketCanSource::write refuses them on purpose.
int sendErrorFrame(uint32_t classes, std::initializer_list<uint8_t> data) {
  const int s = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (s < 0) return errno;
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(if_nametoindex("vcan0"));
  can_frame f{};
  f.can_id = CAN_ERR_FLAG | classes;
  f.len = CAN_ERR_DLC;
  int i = 0;
  for (uint8_t b : data) f.data[i++] = b;
  int e = 0;
  if (::bind(s, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 || ::write(s, &f, sizeof f) != sizeof f) e = errno;
  ::close(s);
  return e;
}

// A controller going bus-off on a real vcan bus and coming back: the error
// frames are read and decoded as such, the interface going down is LinkDown
// (not a dead source), and once it is up again the same source reads frames.
TEST(SocketCan, BusOffAndALinkDownOnVcanIfPresent) {
  if (probeAfCan() != 0) GTEST_SKIP() << "no AF_CAN on this kernel";
  SocketCanSource rx, tx;
  SocketCanDesc desc;
  desc.iface = "vcan0";
  std::string err;
  if (rx.open(desc, err) != BLVD_OK) GTEST_SKIP() << err;
  ASSERT_EQ(tx.open(desc, err), BLVD_OK) << err;
  ASSERT_EQ(sendErrorFrame(CAN_ERR_CRTL | CAN_ERR_CNT, {0, CAN_ERR_CRTL_TX_PASSIVE, 0, 0, 0, 0, 140, 3}), 0);
  ASSERT_EQ(sendErrorFrame(CAN_ERR_BUSOFF, {}), 0);
  Frame got;
  ASSERT_EQ(rx.read(got, 1000, err), SocketCanSource::Result::Frame) << err;
  ASSERT_TRUE(got.error);
  EXPECT_EQ(describe(decodeErrorFrame(got)), "controller problem: tx error-passive; tx errors 140, rx errors 3");
  ASSERT_EQ(rx.read(got, 1000, err), SocketCanSource::Result::Frame) << err;
  ASSERT_TRUE(got.error);
  EXPECT_TRUE(decodeErrorFrame(got).bus_off);

  // The bus goes away (a stopped controller's interface, a pulled link).
  ASSERT_EQ(setLink("vcan0", false), 0) << "needs CAP_NET_ADMIN (the guest runs as root)";
  EXPECT_EQ(rx.read(got, 1000, err), SocketCanSource::Result::LinkDown) << err;
  EXPECT_NE(err.find("the interface went down"), std::string::npos) << err;
  EXPECT_EQ(rx.linkDowns(), 1u);
  Frame f;
  std::string reason;
  ASSERT_TRUE(parseFrame("123#0102", f, reason));
  EXPECT_NE(tx.write(f, err), BLVD_OK);  // nothing can be sent meanwhile
  EXPECT_EQ(rx.read(got, 100, err), SocketCanSource::Result::Timeout) << err;

  // It returns, with the controller restarted: the same sockets carry on.
  ASSERT_EQ(setLink("vcan0", true), 0);
  ASSERT_EQ(sendErrorFrame(CAN_ERR_RESTARTED, {}), 0);
  ASSERT_EQ(tx.write(f, err), BLVD_OK) << err;
  ASSERT_EQ(rx.read(got, 1000, err), SocketCanSource::Result::Frame) << err;
  EXPECT_TRUE(decodeErrorFrame(got).restarted);
  ASSERT_EQ(rx.read(got, 1000, err), SocketCanSource::Result::Frame) << err;
  EXPECT_EQ(formatFrame(got), "123#0102");
  EXPECT_EQ(rx.linkDowns(), 1u);
}

Frame errorFrame(uint32_t classes, std::initializer_list<uint8_t> data) {
  Frame f;
  f.error = true;
  f.id = classes;
  f.dlc = CAN_ERR_DLC;
  int i = 0;
  for (uint8_t b : data) f.data[i++] = b;
  return f;
}

TEST(SocketCan, DecodesBusOff) {
  const ErrorReport r = decodeErrorFrame(errorFrame(CAN_ERR_BUSOFF, {}));
  EXPECT_TRUE(r.bus_off);
  EXPECT_FALSE(r.controller || r.protocol || r.errorPassive());
  EXPECT_EQ(describe(r), "bus-off");
}

TEST(SocketCan, DecodesControllerProblems) {
  // What a controller reports when its tx error counter passes 127: error-passive, with counters.
  const ErrorReport r =
      decodeErrorFrame(errorFrame(CAN_ERR_CRTL | CAN_ERR_CNT,
                                  {0, CAN_ERR_CRTL_TX_PASSIVE | CAN_ERR_CRTL_RX_WARNING, 0, 0, 0, 0, 135, 97}));
  EXPECT_TRUE(r.controller);
  EXPECT_TRUE(r.tx_passive);
  EXPECT_TRUE(r.errorPassive());
  EXPECT_TRUE(r.rx_warning);
  EXPECT_FALSE(r.rx_passive || r.bus_off);
  EXPECT_TRUE(r.has_counters);
  EXPECT_EQ(r.tx_errors, 135);
  EXPECT_EQ(r.rx_errors, 97);
  EXPECT_EQ(describe(r), "controller problem: tx error-passive, rx error-warning; tx errors 135, rx errors 97");

  const ErrorReport o = decodeErrorFrame(errorFrame(CAN_ERR_CRTL, {0, CAN_ERR_CRTL_RX_OVERFLOW}));
  EXPECT_TRUE(o.rx_overflow);
  EXPECT_FALSE(o.has_counters);
  EXPECT_EQ(describe(o), "controller problem: rx buffer overflow");
  const ErrorReport a = decodeErrorFrame(errorFrame(CAN_ERR_CRTL | CAN_ERR_RESTARTED, {0, CAN_ERR_CRTL_ACTIVE}));
  EXPECT_TRUE(a.back_to_active && a.restarted);
  EXPECT_EQ(describe(a), "controller restarted; controller problem: back to error-active");
}

TEST(SocketCan, DecodesProtocolAndOtherClasses) {
  const ErrorReport p = decodeErrorFrame(errorFrame(
      CAN_ERR_PROT | CAN_ERR_BUSERROR, {0, 0, CAN_ERR_PROT_STUFF | CAN_ERR_PROT_TX, CAN_ERR_PROT_LOC_ID28_21}));
  EXPECT_TRUE(p.protocol && p.bus_error);
  EXPECT_EQ(p.protocol_type, CAN_ERR_PROT_STUFF | CAN_ERR_PROT_TX);
  EXPECT_EQ(p.protocol_location, CAN_ERR_PROT_LOC_ID28_21);
  EXPECT_EQ(describe(p), "protocol violation: stuff error, during transmission, at ID bits 28-21; bus error");

  const ErrorReport x = decodeErrorFrame(
      errorFrame(CAN_ERR_LOSTARB | CAN_ERR_ACK | CAN_ERR_TX_TIMEOUT | CAN_ERR_TRX, {5, 0, 0, 0, 0x04}));
  EXPECT_TRUE(x.lost_arbitration && x.no_ack && x.tx_timeout && x.transceiver);
  EXPECT_EQ(x.arbitration_bit, 5);
  EXPECT_EQ(x.transceiver_status, CAN_ERR_TRX_CANH_NO_WIRE);
  EXPECT_EQ(describe(x),
            "transceiver status 0x04; lost arbitration at bit 5; tx timeout; no ACK on transmission");

  // Not an error frame: nothing to report.
  Frame plain;
  plain.id = CAN_ERR_BUSOFF;
  EXPECT_EQ(decodeErrorFrame(plain).classes, 0u);
}

TEST(SocketCan, ErrorFramesFromACandumpLog) {
  // candump logs error frames with CAN_ERR_FLAG in an 8-digit id; the same decoder reads them.
  Frame f;
  std::string reason;
  ASSERT_TRUE(parseFrame("20000044#0020000000000000", f, reason)) << reason;
  const ErrorReport r = decodeErrorFrame(f);
  EXPECT_TRUE(r.bus_off);
  EXPECT_TRUE(r.tx_passive);
  EXPECT_EQ(describe(r), "bus-off; controller problem: tx error-passive");
}

}  // namespace
}  // namespace blvd::can
