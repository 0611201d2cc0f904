// HTTP range requests through libcurl; the contract is in range_client.h.
#include "remote/range_client.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <mutex>
#include <thread>

#include <curl/curl.h>
#include <sys/socket.h>

namespace blvd::remote {
namespace {

using Clock = std::chrono::steady_clock;

// "Name: value\r\n" -> value when the name matches (case-insensitive).
bool headerValue(const std::string& line, const char* name, std::string& value) {
  const size_t n = std::strlen(name);
  if (line.size() <= n || line[n] != ':' || strncasecmp(line.c_str(), name, n) != 0) return false;
  size_t b = n + 1, e = line.size();
  while (b < e && (line[b] == ' ' || line[b] == '\t')) ++b;
  while (e > b && (line[e - 1] == '\r' || line[e - 1] == '\n' || line[e - 1] == ' ')) --e;
  value = line.substr(b, e - b);
  return true;
}

// With a bandwidth cap (paced in Attempt::onBody), a small receive buffer: TCP's window then holds the
// sender to the cap too, instead of the kernel buffering megabytes at the
// link's full speed that libcurl's pacing only reads later.
int smallReceiveBuffer(void* cap, curl_socket_t fd, curlsocktype) {
  const int bytes = int(std::clamp<uint64_t>(*static_cast<uint64_t*>(cap) / 4, 4096, 65536));
  ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &bytes, sizeof bytes);
  return CURL_SOCKOPT_OK;
}

void globalInit() {
  static std::once_flag once;
  std::call_once(once, [] { curl_global_init(CURL_GLOBAL_DEFAULT); });
}

}  // namespace

// One request's state, filled by libcurl's callbacks.
struct RangeClient::Attempt {
  uint64_t offset = 0, size = 0;
  std::vector<uint8_t>* out = nullptr;
  long status = 0;
  std::string etag, retry_after;
  uint64_t range_first = 0, range_last = 0, range_total = 0;
  bool has_range = false;
  uint64_t content_length = 0;
  uint64_t received = 0, filled = 0;
  bool enough = false;  // a 200 answer reached the range's end: stopped on purpose
  uint64_t cap = 0;     // bytes per second, 0: none
  Clock::time_point t0 = Clock::now();

  // The cap, paced here: libcurl's own (CURLOPT_MAX_RECV_SPEED_LARGE) lets a
  // transfer that fits its read loop through unpaced. Sleeping in the write
  // callback stops reading, the small receive window fills, and TCP holds
  // the sender back.
  void pace() const {
    if (cap == 0) return;
    const double ahead = double(received) / double(cap) - std::chrono::duration<double>(Clock::now() - t0).count();
    if (ahead > 0) std::this_thread::sleep_for(std::chrono::duration<double>(ahead));
  }

  static Attempt start(uint64_t offset, uint64_t size, std::vector<uint8_t>* out) {
    Attempt a;
    a.offset = offset, a.size = size, a.out = out;
    return a;
  }

  static size_t onHeader(char* data, size_t size, size_t n, void* self) {
    auto& a = *static_cast<Attempt*>(self);
    const std::string line(data, size * n);
    std::string v;
    if (line.rfind("HTTP/", 0) == 0) {  // a new response (after a redirect or 100): start over
      const uint64_t cap = a.cap;
      a = Attempt::start(a.offset, a.size, a.out);
      a.cap = cap;
      const size_t sp = line.find(' ');
      a.status = sp == std::string::npos ? 0 : std::strtol(line.c_str() + sp + 1, nullptr, 10);
    } else if (headerValue(line, "ETag", v)) {
      a.etag = v;
    } else if (headerValue(line, "Content-Length", v)) {
      a.content_length = std::strtoull(v.c_str(), nullptr, 10);
    } else if (headerValue(line, "Retry-After", v)) {
      a.retry_after = v;
    } else if (headerValue(line, "Content-Range", v)) {
      unsigned long long f = 0, l = 0, t = 0;
      a.has_range = std::sscanf(v.c_str(), "bytes %llu-%llu/%llu", &f, &l, &t) == 3;
      a.range_first = f, a.range_last = l, a.range_total = t;
    }
    return size * n;
  }

  static size_t onBody(char* data, size_t size, size_t n, void* self) {
    auto& a = *static_cast<Attempt*>(self);
    const uint64_t len = size * n, at = a.received;
    a.received += len;
    a.pace();
    // Where these bytes sit in the file: a 206 body starts at the range's
    // offset, a 200 body at 0.
    const uint64_t file_at = a.status == 206 ? a.offset + at : at;
    if (a.status != 206 && a.status != 200) return len;  // an error page: counted, not kept
    const uint64_t lo = std::max(file_at, a.offset), hi = std::min(file_at + len, a.offset + a.size);
    if (lo < hi) {
      std::memcpy(a.out->data() + (lo - a.offset), data + (lo - file_at), hi - lo);
      a.filled += hi - lo;
    }
    if (a.status == 200 && file_at + len >= a.offset + a.size) {
      a.enough = true;
      return 0;  // the rest of the file is not wanted: abort the transfer
    }
    return len;
  }
};

RangeClient::RangeClient(std::string url, LinkOptions opt) : url_(std::move(url)), opt_(opt) {
  globalInit();
  curl_ = curl_easy_init();
}

RangeClient::~RangeClient() {
  if (curl_) curl_easy_cleanup(static_cast<CURL*>(curl_));
}

RangeClient::Outcome RangeClient::attempt(uint64_t offset, uint64_t size, std::vector<uint8_t>& out, double& wait_s,
                                          core::Status& st, std::string& why) {
  CURL* c = static_cast<CURL*>(curl_);
  Attempt a = Attempt::start(offset, size, &out);
  a.cap = opt_.max_bytes_per_s;
  const std::string range = std::to_string(offset) + "-" + std::to_string(offset + size - 1);
  curl_slist* headers = nullptr;
  if (!etag_.empty()) headers = curl_slist_append(headers, ("If-Match: " + etag_).c_str());
  curl_easy_reset(c);
  curl_easy_setopt(c, CURLOPT_URL, url_.c_str());
  curl_easy_setopt(c, CURLOPT_RANGE, range.c_str());
  curl_easy_setopt(c, CURLOPT_HTTPHEADER, headers);
  curl_easy_setopt(c, CURLOPT_NOSIGNAL, 1L);
  curl_easy_setopt(c, CURLOPT_FOLLOWLOCATION, 1L);
  curl_easy_setopt(c, CURLOPT_CONNECTTIMEOUT_MS, long(opt_.connect_timeout_s * 1000));
  curl_easy_setopt(c, CURLOPT_LOW_SPEED_LIMIT, 1L);
  curl_easy_setopt(c, CURLOPT_LOW_SPEED_TIME, std::max(1L, long(std::ceil(opt_.stall_timeout_s))));
  if (opt_.max_bytes_per_s) {
    curl_easy_setopt(c, CURLOPT_SOCKOPTFUNCTION, &smallReceiveBuffer);
    curl_easy_setopt(c, CURLOPT_SOCKOPTDATA, &opt_.max_bytes_per_s);
  }
  curl_easy_setopt(c, CURLOPT_HEADERFUNCTION, &Attempt::onHeader);
  curl_easy_setopt(c, CURLOPT_HEADERDATA, &a);
  curl_easy_setopt(c, CURLOPT_WRITEFUNCTION, &Attempt::onBody);
  curl_easy_setopt(c, CURLOPT_WRITEDATA, &a);
  const CURLcode rc = curl_easy_perform(c);
  curl_slist_free_all(headers);
  ++stats_.requests;
  stats_.bytes += a.received;
  wait_s = 0;
  if (rc != CURLE_OK && !(rc == CURLE_WRITE_ERROR && a.enough)) {
    why = curl_easy_strerror(rc);
    if (rc == CURLE_UNSUPPORTED_PROTOCOL || rc == CURLE_URL_MALFORMAT) return st = core::Status::InvalidArg, Outcome::Fail;
    return Outcome::Retry;
  }
  const std::string code = "HTTP " + std::to_string(a.status);
  if (a.status == 412 || (!etag_.empty() && !a.etag.empty() && a.etag != etag_)) {
    changed_ = true;
    why = "the package changed on the server (ETag " + etag_ + " -> " + (a.etag.empty() ? code : a.etag) + ")";
    return st = core::Status::Corrupt, Outcome::Fail;
  }
  if (a.status == 206 || a.status == 200) {
    const uint64_t end = a.status == 206 ? a.range_last + 1 : a.received;
    if (allow_short_ && end < offset + size && end > offset && (a.status == 200 ? rc == CURLE_OK : a.range_last + 1 == a.range_total)) {
      size = end - offset;  // the file ends inside the range: what there is
      out.resize(size);
    }
    const bool right_range = a.status == 200 || (a.has_range && a.range_first == offset && a.range_last == offset + size - 1);
    if (!right_range) return why = code + " with Content-Range for another range", Outcome::Retry;
    if (a.filled != size) {
      if (a.status == 200 && a.received < offset + size && a.received > 0 && rc == CURLE_OK)
        return why = "range beyond the file's " + std::to_string(a.received) + " bytes", st = core::Status::InvalidArg,
               Outcome::Fail;
      return why = code + " cut after " + std::to_string(a.filled) + " of " + std::to_string(size) + " bytes", Outcome::Retry;
    }
    if (etag_.empty()) etag_ = a.etag;
    if (a.has_range) total_ = a.range_total;
    if (a.status == 200) total_ = a.content_length;  // the whole file's length
    return Outcome::Done;
  }
  why = code;
  if (a.status == 404) return st = core::Status::NotFound, Outcome::Fail;
  if (a.status == 416) return why += " (range beyond the file)", st = core::Status::InvalidArg, Outcome::Fail;
  if (a.status == 429 || a.status == 503) {
    char* end = nullptr;
    const double s = std::strtod(a.retry_after.c_str(), &end);
    if (!a.retry_after.empty() && end && *end == '\0' && s >= 0) wait_s = std::min(s, opt_.retry_after_max_s);
    return Outcome::Retry;
  }
  if (a.status == 408 || a.status >= 500) return Outcome::Retry;
  return st = core::Status::Io, Outcome::Fail;
}

core::Status RangeClient::fetch(uint64_t offset, uint64_t size, std::vector<uint8_t>& out, std::string& err) {
  allow_short_ = false;
  return fetchRange(offset, size, out, err);
}

core::Status RangeClient::fetchUpTo(uint64_t offset, uint64_t size, std::vector<uint8_t>& out, std::string& err) {
  allow_short_ = true;
  const core::Status st = fetchRange(offset, size, out, err);
  allow_short_ = false;
  return st;
}

core::Status RangeClient::fetchRange(uint64_t offset, uint64_t size, std::vector<uint8_t>& out, std::string& err) {
  if (!curl_) return err = url_ + ": libcurl could not start", core::Status::Internal;
  out.assign(size, 0);
  if (size == 0) return core::Status::Ok;
  const auto t0 = Clock::now();
  double backoff = opt_.backoff_s;
  std::string why;
  core::Status st = core::Status::Io;
  bool gave_up = false;
  for (int k = 1; k <= opt_.max_attempts; ++k) {
    double wait_s = 0;
    st = core::Status::Io;
    const Outcome o = attempt(offset, size, out, wait_s, st, why);
    if (o == Outcome::Done) ++stats_.fetches;
    if (o == Outcome::Retry && k < opt_.max_attempts) ++stats_.retries;
    if (on_attempt_) on_attempt_(stats_);
    if (o == Outcome::Done) {
      stats_.seconds += std::chrono::duration<double>(Clock::now() - t0).count();
      return core::Status::Ok;
    }
    if (o == Outcome::Fail) break;
    if (k == opt_.max_attempts) {
      gave_up = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::duration<double>(std::max(wait_s, backoff)));
    backoff = std::min(2 * backoff, opt_.backoff_max_s);
  }
  stats_.seconds += std::chrono::duration<double>(Clock::now() - t0).count();
  err = url_ + ": bytes " + std::to_string(offset) + "-" + std::to_string(offset + size - 1) + ": " + why;
  if (gave_up) err += " (gave up after " + std::to_string(opt_.max_attempts) + " attempts)";
  out.clear();
  return st;
}

}  // namespace blvd::remote
