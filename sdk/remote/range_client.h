// RangeClient: byte ranges of one package over HTTP(S), through libcurl,
// for a car whose link is slow, drops at handovers and disappears in
// tunnels (Marvie et al. stream a city cell by cell the same way; PMTiles
// reads its archives with range requests).
//
// A fetch either returns exactly the bytes asked for or fails with a clear
// error; it never returns bytes of another version of the package:
//  - the first response pins the resource's ETag; every later request sends
//    If-Match with it, and a 412 or a different ETag ends in Status::Corrupt
//    with changed() true (the caller rebuilds for the new package);
//  - 206 must carry the Content-Range asked for; a server that ignores Range
//    and answers 200 with the whole file is read only up to the range's end;
//  - a response cut mid-body, a timeout, a refused connection or a 5xx is
//    retried with exponential backoff (429/503 wait for Retry-After instead),
//    up to max_attempts; a 4xx other than 408/412/429 is not retried.
//
// Threading: one thread at a time (the loader's). Memory: one easy handle,
// its connection reused across fetches.
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/status.h"

namespace blvd::remote {

struct LinkOptions {
  double connect_timeout_s = 5.0;
  double stall_timeout_s = 5.0;    // no byte for this long: the attempt fails (a tunnel)
  int max_attempts = 5;            // tries per fetch, the first included
  double backoff_s = 0.25;         // wait before the second try, doubled each time ...
  double backoff_max_s = 8.0;      // ... up to this
  double retry_after_max_s = 60.0; // a server's Retry-After is honoured up to this
  uint64_t max_bytes_per_s = 0;    // bandwidth cap (0: none), paced as the body arrives
};

struct LinkStats {
  uint64_t requests = 0;    // HTTP requests made, retries included
  uint64_t bytes = 0;       // body bytes received (a 200 answer's unused part included)
  uint64_t retries = 0;     // attempts after a failed one
  uint64_t fetches = 0;     // fetch() calls that succeeded
  double seconds = 0;       // spent in requests and backoff waits
};

class RangeClient {
 public:
  explicit RangeClient(std::string url, LinkOptions opt = {});
  ~RangeClient();
  RangeClient(const RangeClient&) = delete;
  RangeClient& operator=(const RangeClient&) = delete;

  // Bytes [offset, offset + size) of the resource into `out` (resized to
  // size). Io when the link gave up (err says the last failure and the
  // attempts), NotFound for 404, InvalidArg for a range beyond the file
  // (416), Corrupt when the resource changed (changed() is then true).
  core::Status fetch(uint64_t offset, uint64_t size, std::vector<uint8_t>& out, std::string& err);
  // The same, but a range that runs past the file's end gives the bytes up
  // to the end (out is shorter), as HTTP serves it: for a first read of a
  // file whose size is not known yet.
  core::Status fetchUpTo(uint64_t offset, uint64_t size, std::vector<uint8_t>& out, std::string& err);

  const std::string& url() const { return url_; }
  const std::string& etag() const { return etag_; }   // pinned by the first response ("" until then)
  uint64_t resourceBytes() const { return total_; }   // from Content-Range (0 until known)
  bool changed() const { return changed_; }
  const LinkStats& stats() const { return stats_; }
  // Called on the fetching thread after every attempt with the stats so far,
  // so that a fetch retrying through a tunnel shows its requests as they go.
  void onAttempt(std::function<void(const LinkStats&)> f) { on_attempt_ = std::move(f); }

 private:
  struct Attempt;
  enum class Outcome { Done, Retry, Fail };
  Outcome attempt(uint64_t offset, uint64_t size, std::vector<uint8_t>& out, double& wait_s, core::Status& st,
                  std::string& why);
  core::Status fetchRange(uint64_t offset, uint64_t size, std::vector<uint8_t>& out, std::string& err);

  std::string url_;
  LinkOptions opt_;
  void* curl_ = nullptr;  // CURL*
  std::string etag_;
  uint64_t total_ = 0;
  bool changed_ = false;
  bool allow_short_ = false;  // fetchUpTo: a range past the end is served to the end
  LinkStats stats_;
  std::function<void(const LinkStats&)> on_attempt_;
};

}  // namespace blvd::remote
