#include "core/status.h"

namespace blvd::core {

const char* statusString(Status s) {
  switch (s) {
    case Status::Ok: return "ok";
    case Status::Misuse: return "API misuse";
    case Status::InvalidArg: return "invalid argument";
    case Status::Io: return "I/O error";
    case Status::Corrupt: return "corrupt input";
    case Status::NoMem: return "out of memory";
    case Status::Backend: return "no usable GL backend";
    case Status::Budget: return "memory budget too small";
    case Status::Unsupported: return "unsupported";
    case Status::Internal: return "internal error";
    case Status::NotFound: return "not found";
    case Status::Timeout: return "timed out";
    case Status::Unavailable: return "not available now (offline or link down)";
    case Status::OffMap: return "pose off the map";
  }
  return "unknown status";
}

}  // namespace blvd::core
