// Where vcan_drive's frames come from: a SocketCAN interface (vcan0, can0) or,
// for a host without CAN, a candump -l log read as fast as possible.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "can/candump.h"
#include "can/socketcan.h"

namespace vcan_drive {

struct CanInputDesc {
  std::string iface;    // SocketCAN interface; used when `candump` is empty
  std::string candump;  // a candump -l log instead of an interface
  std::vector<std::pair<uint32_t, bool>> ids;  // kernel filters (id, extended); empty: everything
  int rcvbuf_bytes = 0;  // socket receive buffer; 0: the kernel's default
};

class CanInput {
 public:
  enum class Result { Frame, Timeout, End, BadLine, Error };

  blvd_status open(const CanInputDesc& desc, std::string& err);
  // Next frame; waits at most timeout_ms on a socket. BadLine: `err` names the
  // skipped log line and reading goes on; Error: `err` says why, nothing more comes.
  Result next(blvd::can::Frame& out, int timeout_ms, std::string& err);

  std::string describe() const;     // "vcan0" or "candump:FILE"
  uint32_t kernelDropped() const { return socket_.dropped(); }
  uint64_t errorFrames() const { return error_frames_; }
  uint64_t busOffs() const { return bus_offs_; }
  uint64_t linkDowns() const { return from_log_ ? 0 : socket_.linkDowns(); }
  uint64_t badLines() const { return reader_.badLineCount(); }

 private:
  CanInputDesc desc_;
  bool from_log_ = false;
  blvd::can::SocketCanSource socket_;
  blvd::can::CandumpReader reader_;
  uint64_t error_frames_ = 0, bus_offs_ = 0;
};

}  // namespace vcan_drive
