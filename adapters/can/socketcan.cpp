#include "can/socketcan.h"

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <cstdio>
#include <cstring>

namespace blvd::can {
namespace {

std::string sysError(const char* what, int e) { return std::string(what) + ": " + std::strerror(e); }

const char* protocolLocation(uint8_t loc) {
  switch (loc) {
    case CAN_ERR_PROT_LOC_SOF: return "start of frame";
    case CAN_ERR_PROT_LOC_ID28_21: return "ID bits 28-21";
    case CAN_ERR_PROT_LOC_ID20_18: return "ID bits 20-18";
    case CAN_ERR_PROT_LOC_SRTR: return "substitute RTR";
    case CAN_ERR_PROT_LOC_IDE: return "identifier extension";
    case CAN_ERR_PROT_LOC_ID17_13: return "ID bits 17-13";
    case CAN_ERR_PROT_LOC_ID12_05: return "ID bits 12-5";
    case CAN_ERR_PROT_LOC_ID04_00: return "ID bits 4-0";
    case CAN_ERR_PROT_LOC_RTR: return "RTR bit";
    case CAN_ERR_PROT_LOC_RES1: return "reserved bit 1";
    case CAN_ERR_PROT_LOC_RES0: return "reserved bit 0";
    case CAN_ERR_PROT_LOC_DLC: return "data length code";
    case CAN_ERR_PROT_LOC_DATA: return "data section";
    case CAN_ERR_PROT_LOC_CRC_SEQ: return "CRC sequence";
    case CAN_ERR_PROT_LOC_CRC_DEL: return "CRC delimiter";
    case CAN_ERR_PROT_LOC_ACK: return "ACK slot";
    case CAN_ERR_PROT_LOC_ACK_DEL: return "ACK delimiter";
    case CAN_ERR_PROT_LOC_EOF: return "end of frame";
    case CAN_ERR_PROT_LOC_INTERM: return "intermission";
    default: return nullptr;
  }
}

void appendList(std::string& out, const char* sep, const std::string& item) {
  if (!out.empty()) out += sep;
  out += item;
}

}  // namespace

ErrorReport decodeErrorFrame(const Frame& f) {
  ErrorReport r;
  if (!f.error) return r;
  const uint32_t c = f.id & CAN_ERR_MASK;
  const uint8_t* d = f.data;
  // The kernel always sends CAN_ERR_DLC (8) bytes; a shorter logged frame reads as zeros.
  uint8_t b[CAN_ERR_DLC] = {};
  std::memcpy(b, d, f.dlc < CAN_ERR_DLC ? f.dlc : CAN_ERR_DLC);
  r.classes = c;
  r.tx_timeout = c & CAN_ERR_TX_TIMEOUT;
  r.lost_arbitration = c & CAN_ERR_LOSTARB;
  if (r.lost_arbitration) r.arbitration_bit = b[0];
  r.controller = c & CAN_ERR_CRTL;
  if (r.controller) {
    r.rx_overflow = b[1] & CAN_ERR_CRTL_RX_OVERFLOW;
    r.tx_overflow = b[1] & CAN_ERR_CRTL_TX_OVERFLOW;
    r.rx_warning = b[1] & CAN_ERR_CRTL_RX_WARNING;
    r.tx_warning = b[1] & CAN_ERR_CRTL_TX_WARNING;
    r.rx_passive = b[1] & CAN_ERR_CRTL_RX_PASSIVE;
    r.tx_passive = b[1] & CAN_ERR_CRTL_TX_PASSIVE;
    r.back_to_active = b[1] & CAN_ERR_CRTL_ACTIVE;
  }
  r.protocol = c & CAN_ERR_PROT;
  if (r.protocol) {
    r.protocol_type = b[2];
    r.protocol_location = b[3];
  }
  r.transceiver = c & CAN_ERR_TRX;
  if (r.transceiver) r.transceiver_status = b[4];
  r.no_ack = c & CAN_ERR_ACK;
  r.bus_off = c & CAN_ERR_BUSOFF;
  r.bus_error = c & CAN_ERR_BUSERROR;
  r.restarted = c & CAN_ERR_RESTARTED;
#ifdef CAN_ERR_CNT
  r.has_counters = c & CAN_ERR_CNT;
#else
  r.has_counters = c & 0x200u;  // CAN_ERR_CNT, Linux 6.1 and later
#endif
  if (r.has_counters) {
    r.tx_errors = b[6];
    r.rx_errors = b[7];
  }
  return r;
}

std::string describe(const ErrorReport& r) {
  std::string s;
  if (r.bus_off) appendList(s, "; ", "bus-off");
  if (r.restarted) appendList(s, "; ", "controller restarted");
  if (r.controller) {
    std::string c;
    if (r.rx_passive) appendList(c, ", ", "rx error-passive");
    if (r.tx_passive) appendList(c, ", ", "tx error-passive");
    if (r.rx_warning) appendList(c, ", ", "rx error-warning");
    if (r.tx_warning) appendList(c, ", ", "tx error-warning");
    if (r.rx_overflow) appendList(c, ", ", "rx buffer overflow");
    if (r.tx_overflow) appendList(c, ", ", "tx buffer overflow");
    if (r.back_to_active) appendList(c, ", ", "back to error-active");
    appendList(s, "; ", "controller problem" + (c.empty() ? std::string() : ": " + c));
  }
  if (r.protocol) {
    std::string p;
    static const struct {
      uint8_t bit;
      const char* name;
    } kTypes[] = {{CAN_ERR_PROT_BIT, "bit error"},       {CAN_ERR_PROT_FORM, "form error"},
                  {CAN_ERR_PROT_STUFF, "stuff error"},   {CAN_ERR_PROT_BIT0, "unable to send dominant bit"},
                  {CAN_ERR_PROT_BIT1, "unable to send recessive bit"}, {CAN_ERR_PROT_OVERLOAD, "bus overload"},
                  {CAN_ERR_PROT_ACTIVE, "active error announcement"},  {CAN_ERR_PROT_TX, "during transmission"}};
    for (const auto& t : kTypes)
      if (r.protocol_type & t.bit) appendList(p, ", ", t.name);
    if (const char* loc = protocolLocation(r.protocol_location)) appendList(p, ", ", std::string("at ") + loc);
    appendList(s, "; ", "protocol violation" + (p.empty() ? std::string() : ": " + p));
  }
  if (r.transceiver) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "transceiver status 0x%02X", r.transceiver_status);
    appendList(s, "; ", buf);
  }
  if (r.lost_arbitration)
    appendList(s, "; ", "lost arbitration" + (r.arbitration_bit ? " at bit " + std::to_string(r.arbitration_bit) : ""));
  if (r.tx_timeout) appendList(s, "; ", "tx timeout");
  if (r.no_ack) appendList(s, "; ", "no ACK on transmission");
  if (r.bus_error) appendList(s, "; ", "bus error");
  if (r.has_counters)
    appendList(s, "; ", "tx errors " + std::to_string(r.tx_errors) + ", rx errors " + std::to_string(r.rx_errors));
  if (s.empty()) s = "error frame without a known class";
  return s;
}

SocketCanSource::~SocketCanSource() { close(); }

SocketCanSource::SocketCanSource(SocketCanSource&& o) noexcept
    : fd_(o.fd_), fd_frames_(o.fd_frames_), bound_iface_(std::move(o.bound_iface_)), names_(std::move(o.names_)),
      dropped_(o.dropped_), link_downs_(o.link_downs_) {
  o.fd_ = -1;
}

SocketCanSource& SocketCanSource::operator=(SocketCanSource&& o) noexcept {
  if (this != &o) {
    close();
    fd_ = o.fd_;
    fd_frames_ = o.fd_frames_;
    bound_iface_ = std::move(o.bound_iface_);
    names_ = std::move(o.names_);
    dropped_ = o.dropped_;
    link_downs_ = o.link_downs_;
    o.fd_ = -1;
  }
  return *this;
}

void SocketCanSource::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  names_.clear();
}

blvd_status SocketCanSource::open(const SocketCanDesc& desc, std::string& err) {
  close();
  const int s = ::socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);
  if (s < 0) {
    const int e = errno;
    if (e == EAFNOSUPPORT) {
      err = "AF_CAN not supported by this kernel (socket(PF_CAN, SOCK_RAW, CAN_RAW): " + std::string(std::strerror(e)) +
            "); load the can and can_raw modules (modprobe can_raw) or run on a kernel with CONFIG_CAN";
      return BLVD_ERR_UNSUPPORTED;
    }
    if (e == EPROTONOSUPPORT) {
      err = "CAN_RAW not supported by this kernel (socket(PF_CAN, SOCK_RAW, CAN_RAW): " + std::string(std::strerror(e)) +
            "); load the can_raw module";
      return BLVD_ERR_UNSUPPORTED;
    }
    err = sysError("socket(PF_CAN, SOCK_RAW, CAN_RAW)", e);
    return BLVD_ERR_IO;
  }
  const auto failWith = [&](blvd_status st, std::string text) {
    ::close(s);
    err = std::move(text);
    return st;
  };

  int ifindex = 0;  // 0: every CAN interface
  const bool any = desc.iface.empty() || desc.iface == "any";
  if (!any) {
    if (desc.iface.size() >= IFNAMSIZ)
      return failWith(BLVD_ERR_INVALID_ARG, "interface name '" + desc.iface + "' is longer than " +
                                                std::to_string(IFNAMSIZ - 1) + " characters");
    ifindex = static_cast<int>(if_nametoindex(desc.iface.c_str()));
    if (ifindex == 0)
      return failWith(BLVD_ERR_NOT_FOUND, "no network interface named '" + desc.iface + "' (" + std::strerror(errno) +
                                              "); for a virtual one: ip link add dev " + desc.iface +
                                              " type vcan && ip link set up " + desc.iface);
  }

  if (!desc.filters.empty()) {
    std::vector<can_filter> f(desc.filters.size());
    for (size_t i = 0; i < f.size(); ++i) {
      const CanFilter& in = desc.filters[i];
      // CAN_EFF_FLAG in the mask makes the filter match only one kind of id.
      f[i].can_id = (in.id & (in.extended ? CAN_EFF_MASK : CAN_SFF_MASK)) | (in.extended ? CAN_EFF_FLAG : 0u);
      f[i].can_mask = (in.mask & (in.extended ? CAN_EFF_MASK : CAN_SFF_MASK)) | CAN_EFF_FLAG | CAN_RTR_FLAG;
      if (in.inverted) f[i].can_id |= CAN_INV_FILTER;
    }
    if (setsockopt(s, SOL_CAN_RAW, CAN_RAW_FILTER, f.data(), static_cast<socklen_t>(f.size() * sizeof(can_filter))) <
        0)
      return failWith(BLVD_ERR_IO, sysError("setsockopt(CAN_RAW_FILTER)", errno));
  }
  if (!desc.no_error_frames) {
    const can_err_mask_t mask = desc.error_mask ? (desc.error_mask & CAN_ERR_MASK) : CAN_ERR_MASK;
    if (setsockopt(s, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &mask, sizeof mask) < 0)
      return failWith(BLVD_ERR_IO, sysError("setsockopt(CAN_RAW_ERR_FILTER)", errno));
  }
  if (desc.fd) {
    const int on = 1;
    if (setsockopt(s, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on) < 0)
      return failWith(BLVD_ERR_UNSUPPORTED, sysError("setsockopt(CAN_RAW_FD_FRAMES): CAN FD not supported", errno));
  }
  // Nanosecond kernel timestamps where available, else microseconds.
  const int on = 1;
  if (setsockopt(s, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on) < 0 &&
      setsockopt(s, SOL_SOCKET, SO_TIMESTAMP, &on, sizeof on) < 0)
    return failWith(BLVD_ERR_IO, sysError("setsockopt(SO_TIMESTAMP)", errno));
  (void)setsockopt(s, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on);  // drop counter; optional

  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = ifindex;
  if (bind(s, reinterpret_cast<sockaddr*>(&addr), sizeof addr) < 0)
    return failWith(BLVD_ERR_IO, sysError(("bind to " + (any ? std::string("every CAN interface") : desc.iface)).c_str(),
                                          errno));
  fd_ = s;
  fd_frames_ = desc.fd;
  bound_iface_ = any ? std::string() : desc.iface;
  dropped_ = 0;
  link_downs_ = 0;
  return BLVD_OK;
}

const std::string& SocketCanSource::ifaceName(int ifindex) {
  if (!bound_iface_.empty()) return bound_iface_;
  auto it = names_.find(ifindex);
  if (it == names_.end()) {
    char buf[IF_NAMESIZE] = {};
    std::string name = if_indextoname(static_cast<unsigned>(ifindex), buf) ? buf : "if" + std::to_string(ifindex);
    it = names_.emplace(ifindex, std::move(name)).first;
  }
  return it->second;
}

SocketCanSource::Result SocketCanSource::read(Frame& out, int timeout_ms, std::string& err) {
  if (fd_ < 0) {
    err = "SocketCAN source is not open";
    return Result::Error;
  }
  pollfd p{fd_, POLLIN, 0};
  for (;;) {
    const int n = ::poll(&p, 1, timeout_ms < 0 ? -1 : timeout_ms);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      err = sysError("poll", errno);
      return Result::Error;
    }
    if (n == 0) return Result::Timeout;
    break;
  }
  canfd_frame frame{};
  sockaddr_can addr{};
  iovec iov{&frame, sizeof frame};
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(timeval)) +
                                CMSG_SPACE(sizeof(uint32_t))];
  msghdr msg{};
  msg.msg_name = &addr;
  msg.msg_namelen = sizeof addr;
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof control;
  ssize_t nbytes;
  do {
    nbytes = recvmsg(fd_, &msg, 0);
  } while (nbytes < 0 && errno == EINTR);
  if (nbytes < 0) {
    const int e = errno;
    if (e == EAGAIN || e == EWOULDBLOCK) return Result::Timeout;
    err = sysError("recvmsg", e);
    if (e != ENETDOWN) return Result::Error;
    err += " (the interface went down)";
    ++link_downs_;
    return Result::LinkDown;
  }
  if (nbytes != static_cast<ssize_t>(CAN_MTU) && nbytes != static_cast<ssize_t>(CANFD_MTU)) {
    err = "recvmsg: unexpected frame size " + std::to_string(nbytes);
    return Result::Error;
  }

  double t = -1;
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c; c = CMSG_NXTHDR(&msg, c)) {
    if (c->cmsg_level != SOL_SOCKET) continue;
    if (c->cmsg_type == SCM_TIMESTAMPNS) {
      timespec ts;
      std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
      t = static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
    } else if (c->cmsg_type == SCM_TIMESTAMP) {
      timeval tv;
      std::memcpy(&tv, CMSG_DATA(c), sizeof tv);
      t = static_cast<double>(tv.tv_sec) + static_cast<double>(tv.tv_usec) * 1e-6;
    } else if (c->cmsg_type == SO_RXQ_OVFL) {
      std::memcpy(&dropped_, CMSG_DATA(c), sizeof dropped_);
    }
  }
  if (t < 0) {  // no kernel timestamp: the best we have is now
    timespec now;
    clock_gettime(CLOCK_REALTIME, &now);
    t = static_cast<double>(now.tv_sec) + static_cast<double>(now.tv_nsec) * 1e-9;
  }

  Frame f;
  f.t = t;
  const canid_t id = frame.can_id;
  f.error = id & CAN_ERR_FLAG;
  f.extended = !f.error && (id & CAN_EFF_FLAG);
  f.rtr = !f.error && (id & CAN_RTR_FLAG);
  f.id = f.error ? (id & CAN_ERR_MASK) : f.extended ? (id & CAN_EFF_MASK) : (id & CAN_SFF_MASK);
  f.fd = nbytes == static_cast<ssize_t>(CANFD_MTU);
  const unsigned max = f.fd ? CANFD_MAX_DLEN : CAN_MAX_DLEN;
  f.dlc = static_cast<uint8_t>(frame.len <= max ? frame.len : max);
  if (f.fd) {
    f.fd_flags = frame.flags & 0xF;
  } else {
#ifdef CAN_MAX_RAW_DLC
    // struct can_frame's len8_dlc byte, read from the bytes the kernel wrote.
    uint8_t raw_dlc = 0;
    std::memcpy(&raw_dlc, reinterpret_cast<const unsigned char*>(&frame) + offsetof(can_frame, len8_dlc), 1);
    if (f.dlc == CAN_MAX_DLEN && raw_dlc > CAN_MAX_DLEN && raw_dlc <= CAN_MAX_RAW_DLC) f.len8_dlc = raw_dlc;
#endif
  }
  if (!f.rtr) std::memcpy(f.data, frame.data, f.dlc);
  f.iface = ifaceName(addr.can_ifindex);
  out = std::move(f);
  return Result::Frame;
}

blvd_status SocketCanSource::write(const Frame& f, std::string& err) {
  if (fd_ < 0) {
    err = "SocketCAN source is not open";
    return BLVD_ERR_MISUSE;
  }
  if (f.error) {
    err = "error frames cannot be sent";
    return BLVD_ERR_INVALID_ARG;
  }
  if (f.fd && !fd_frames_) {
    err = "CAN FD frame on a source opened without desc.fd";
    return BLVD_ERR_INVALID_ARG;
  }
  if (f.dlc > (f.fd ? CANFD_MAX_DLEN : CAN_MAX_DLEN) || (f.fd && !isFdLength(f.dlc))) {
    err = "frame length " + std::to_string(f.dlc) + " is not valid";
    return BLVD_ERR_INVALID_ARG;
  }
  canfd_frame frame{};
  frame.can_id = f.extended ? ((f.id & CAN_EFF_MASK) | CAN_EFF_FLAG) : (f.id & CAN_SFF_MASK);
  if (f.rtr && !f.fd) frame.can_id |= CAN_RTR_FLAG;
  frame.len = f.dlc;
  if (f.fd) {
    frame.flags = f.fd_flags & (CANFD_BRS | CANFD_ESI);
  } else {
#ifdef CAN_MAX_RAW_DLC
    if (f.dlc == CAN_MAX_DLEN && f.len8_dlc > CAN_MAX_DLEN && f.len8_dlc <= CAN_MAX_RAW_DLC)
      std::memcpy(reinterpret_cast<unsigned char*>(&frame) + offsetof(can_frame, len8_dlc), &f.len8_dlc, 1);
#endif
  }
  if (!f.rtr) std::memcpy(frame.data, f.data, f.dlc);
  const size_t size = f.fd ? CANFD_MTU : CAN_MTU;
  ssize_t n;
  do {
    n = ::write(fd_, &frame, size);
  } while (n < 0 && errno == EINTR);
  if (n != static_cast<ssize_t>(size)) {
    err = n < 0 ? sysError("write", errno) : "write: short write";
    return BLVD_ERR_IO;
  }
  return BLVD_OK;
}

}  // namespace blvd::can
