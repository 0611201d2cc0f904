// Status codes and errors shared by every module. The numeric values mirror
// blvd_status in include/blvd/blvd.h (append-only), so capi maps them 1:1.
#pragma once
#include <stdexcept>
#include <string>

namespace blvd::core {

enum class Status : int {
  Ok = 0,
  Misuse = 1,       // NULL handle, wrong call order, wrong thread
  InvalidArg = 2,   // an argument or descriptor field is out of range
  Io = 3,           // file cannot be opened, read or written
  Corrupt = 4,      // input data is malformed (package, PBF, GLB ...)
  NoMem = 5,        // an allocation failed
  Backend = 6,      // no GL context backend could be created
  Budget = 7,       // a memory budget is too small
  Unsupported = 8,  // valid input that this build cannot handle
  Internal = 9,     // a bug: an invariant did not hold
  NotFound = 10,    // a requested item does not exist
  Timeout = 11,     // a wait ended before its condition held
  Unavailable = 12, // data not here now: offline, or the link is down; try again later
  OffMap = 13,      // a pose outside the package's streets plus graph::kMapMarginM
};

const char* statusString(Status s);

// Error carries a status plus a message that names the file / offset / line.
// Used inside the C++ modules; sdk/capi converts it to blvd_status + last error.
class Error : public std::runtime_error {
 public:
  Error(Status s, const std::string& msg) : std::runtime_error(msg), status_(s) {}
  Status status() const { return status_; }

 private:
  Status status_;
};

}  // namespace blvd::core
