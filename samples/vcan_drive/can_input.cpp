#include "can_input.h"

#include <sys/socket.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace vcan_drive {

using blvd::can::CandumpReader;
using blvd::can::SocketCanSource;

blvd_status CanInput::open(const CanInputDesc& desc, std::string& err) {
  desc_ = desc;
  from_log_ = !desc.candump.empty();
  if (from_log_) {
    blvd_status st = reader_.open(desc.candump);
    if (st != BLVD_OK) err = reader_.error();
    return st;
  }
  blvd::can::SocketCanDesc sd;
  sd.iface = desc.iface;
  for (const auto& [id, ext] : desc.ids) sd.filters.push_back({id, ext ? blvd::can::kEffMask : blvd::can::kSffMask, ext, false});
  blvd_status st = socket_.open(sd, err);
  if (st != BLVD_OK) return st;
  if (desc.rcvbuf_bytes > 0) {
    // A replay at full rate outruns a slow reader (a TCG guest) by bursts; a
    // larger queue absorbs them. SO_RCVBUFFORCE passes net.core.rmem_max as root.
    const int n = desc.rcvbuf_bytes;
    if (setsockopt(socket_.fd(), SOL_SOCKET, SO_RCVBUFFORCE, &n, sizeof n) != 0 &&
        setsockopt(socket_.fd(), SOL_SOCKET, SO_RCVBUF, &n, sizeof n) != 0)
      std::fprintf(stderr, "vcan_drive: cannot set the receive buffer to %d bytes: %s\n", n, std::strerror(errno));
  }
  return BLVD_OK;
}

CanInput::Result CanInput::next(blvd::can::Frame& out, int timeout_ms, std::string& err) {
  if (from_log_) {
    blvd::can::Record r;
    switch (reader_.next(r)) {
      case CandumpReader::Result::Frame:
        out = std::move(r.frame);
        break;
      case CandumpReader::Result::BadLine:
        err = reader_.error();
        return Result::BadLine;
      case CandumpReader::Result::End:
        return Result::End;
      case CandumpReader::Result::IoError:
        err = reader_.error();
        return Result::Error;
    }
  } else {
    switch (socket_.read(out, timeout_ms, err)) {
      case SocketCanSource::Result::Frame:
        break;
      case SocketCanSource::Result::Timeout:
        return Result::Timeout;
      case SocketCanSource::Result::Error:
        return Result::Error;
      case SocketCanSource::Result::LinkDown:  // reported; the drive waits for the bus to come back
        std::fprintf(stderr, "vcan_drive: %s\n", err.c_str());
        return Result::Timeout;
    }
  }
  if (out.error) {
    ++error_frames_;
    const blvd::can::ErrorReport rep = blvd::can::decodeErrorFrame(out);
    if (rep.bus_off) ++bus_offs_;
    std::fprintf(stderr, "vcan_drive: %s error frame: %s\n", out.iface.c_str(), blvd::can::describe(rep).c_str());
  }
  return Result::Frame;
}

std::string CanInput::describe() const { return from_log_ ? "candump:" + desc_.candump : desc_.iface; }

}  // namespace vcan_drive
