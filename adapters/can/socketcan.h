// Linux SocketCAN source: a CAN_RAW socket bound to one interface (or all),
// with kernel receive filters, kernel timestamps and error frames.
//
// Error frames are switched on with CAN_RAW_ERR_FILTER and come out of read()
// as frames with `error` set; decodeErrorFrame() turns one into an ErrorReport
// (bus-off, error-passive/-warning, controller overflows, protocol violations,
// transceiver faults, error counters), following <linux/can/error.h>.
//
// A kernel without AF_CAN (no `can`/`can_raw` modules, as in many containers)
// makes open() fail with BLVD_ERR_UNSUPPORTED and "AF_CAN not supported by this
// kernel ...". Threading: one source per thread; read() blocks only up to its timeout.
#pragma once

#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "blvd/blvd.h"
#include "can/frame.h"

namespace blvd::can {

// A kernel acceptance filter: a frame passes when (frame_id & mask) == (id & mask).
struct CanFilter {
  uint32_t id = 0;
  uint32_t mask = 0;
  bool extended = false;  // match only 29-bit ids (else only 11-bit ids)
  bool inverted = false;  // pass what does NOT match (CAN_INV_FILTER)
};

// Zero-initialised means: every interface, every frame, error frames on, classic CAN only.
struct SocketCanDesc {
  std::string iface;               // "can0"; "" or "any": every CAN interface
  std::vector<CanFilter> filters;  // empty: receive everything
  bool no_error_frames = false;    // true: do not ask for error frames
  uint32_t error_mask = 0;         // CAN_ERR_* classes to receive; 0: all of them
  bool fd = false;                 // also receive (and allow sending) CAN FD frames
};

// What an error frame says. Class bits are the CAN_ERR_* bits of its id.
struct ErrorReport {
  uint32_t classes = 0;
  bool tx_timeout = false;
  bool lost_arbitration = false;
  uint8_t arbitration_bit = 0;     // bit where arbitration was lost; 0: unknown
  bool controller = false;         // controller problem; the flags below say which
  bool rx_overflow = false, tx_overflow = false;
  bool rx_warning = false, tx_warning = false;   // error counter reached the warning level (96)
  bool rx_passive = false, tx_passive = false;   // error-passive (counter >= 128)
  bool back_to_active = false;                   // recovered to error-active
  bool protocol = false;           // protocol violation
  uint8_t protocol_type = 0;       // CAN_ERR_PROT_* bits (bit, form, stuff, ...)
  uint8_t protocol_location = 0;   // CAN_ERR_PROT_LOC_*
  bool transceiver = false;
  uint8_t transceiver_status = 0;  // CAN_ERR_TRX_*
  bool no_ack = false;
  bool bus_off = false;
  bool bus_error = false;
  bool restarted = false;          // controller restarted after bus-off
  bool has_counters = false;       // CAN_ERR_CNT: the counters below are valid
  uint8_t tx_errors = 0, rx_errors = 0;

  bool errorPassive() const { return rx_passive || tx_passive; }
  bool errorWarning() const { return rx_warning || tx_warning; }
};

// Decodes an error frame (f.error must be set; otherwise the report is empty).
ErrorReport decodeErrorFrame(const Frame& f);
// One line for logs: "bus-off; controller: tx error-passive; tx errors 135, rx errors 0".
std::string describe(const ErrorReport& r);

class SocketCanSource {
 public:
  // LinkDown: the interface went down (ENETDOWN, reported once per going
  // down; a bus-off controller that the kernel stops shows the same). The
  // socket stays bound: keep reading, frames come again when it is back up.
  enum class Result { Frame, Timeout, Error, LinkDown };

  SocketCanSource() = default;
  ~SocketCanSource();
  SocketCanSource(const SocketCanSource&) = delete;
  SocketCanSource& operator=(const SocketCanSource&) = delete;
  SocketCanSource(SocketCanSource&& o) noexcept;
  SocketCanSource& operator=(SocketCanSource&& o) noexcept;

  // Opens and binds the socket. On failure nothing stays open and `err` says why:
  // BLVD_ERR_UNSUPPORTED when the kernel has no AF_CAN / CAN_RAW,
  // BLVD_ERR_NOT_FOUND when there is no such interface, BLVD_ERR_INVALID_ARG
  // for a bad name, BLVD_ERR_IO for other socket errors.
  blvd_status open(const SocketCanDesc& desc, std::string& err);
  void close();
  bool isOpen() const { return fd_ >= 0; }
  // The socket, for a host's own poll()/epoll loop; -1 when closed.
  int fd() const { return fd_; }

  // Waits up to timeout_ms (negative: without limit) for one frame. The frame's
  // t is the kernel receive time (CLOCK_REALTIME, nanoseconds when the kernel
  // gives them) and iface the receiving interface.
  Result read(Frame& out, int timeout_ms, std::string& err);
  // Sends a frame (classic, or FD when desc.fd). BLVD_ERR_IO with `err` on failure.
  blvd_status write(const Frame& f, std::string& err);

  // Frames the kernel dropped because the socket's receive queue was full (SO_RXQ_OVFL).
  uint32_t dropped() const { return dropped_; }
  // Times read() saw the interface go down.
  uint32_t linkDowns() const { return link_downs_; }

 private:
  const std::string& ifaceName(int ifindex);

  int fd_ = -1;
  bool fd_frames_ = false;
  std::string bound_iface_;
  std::unordered_map<int, std::string> names_;
  uint32_t dropped_ = 0;
  uint32_t link_downs_ = 0;
};

}  // namespace blvd::can
