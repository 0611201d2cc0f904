#include "can/candump.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <istream>
#include <ostream>

namespace blvd::can {
namespace {

constexpr uint32_t kErrFlag = 0x20000000u;  // CAN_ERR_FLAG
constexpr uint32_t kIdFlagBits = 0xC0000000u;  // CAN_EFF_FLAG | CAN_RTR_FLAG: never part of a logged id

int nibble(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

constexpr char kHex[] = "0123456789ABCDEF";

void putHex(std::string& s, uint32_t v, int digits) {
  for (int i = digits - 1; i >= 0; --i) s.push_back(kHex[(v >> (4 * i)) & 0xF]);
}

std::string quoted(std::string_view s) {
  std::string q = "'";
  for (char c : s.substr(0, 40)) q.push_back(static_cast<unsigned char>(c) < 0x20 ? '?' : c);
  if (s.size() > 40) q += "...";
  return q + "'";
}

bool fail(std::string& reason, std::string text) {
  reason = std::move(text);
  return false;
}

// Right-aligns `s` in `width` columns, as printf("%*s").
void putPadded(std::string& out, std::string_view s, unsigned width) {
  if (width > s.size()) out.append(width - s.size(), ' ');
  out.append(s);
}

void putStamp(std::string& out, int64_t sec, uint32_t frac, unsigned frac_digits, unsigned sec_width) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "(%0*lld.%0*u)", static_cast<int>(sec_width), static_cast<long long>(sec),
                static_cast<int>(frac_digits), frac);
  out += buf;
}

}  // namespace

bool parseFrame(std::string_view cs, Frame& out, std::string& reason) {
  out.id = 0;
  out.extended = out.rtr = out.error = out.fd = false;
  out.fd_flags = out.dlc = out.len8_dlc = 0;
  std::memset(out.data, 0, sizeof out.data);

  const size_t hash = cs.find('#');
  if (hash == std::string_view::npos) return fail(reason, "no '#' in frame " + quoted(cs));
  if (hash != 3 && hash != 8)
    return fail(reason, "identifier must have 3 or 8 hex digits, not " + std::to_string(hash) + " in " + quoted(cs));
  uint32_t raw = 0;
  for (size_t i = 0; i < hash; ++i) {
    const int n = nibble(cs[i]);
    if (n < 0) return fail(reason, "bad hex digit in identifier " + quoted(cs.substr(0, hash)));
    raw = (raw << 4) | static_cast<uint32_t>(n);
  }
  if (hash == 3) {
    if (raw > kSffMask) return fail(reason, "standard identifier " + quoted(cs.substr(0, 3)) + " exceeds 7FF");
    out.id = raw;
  } else {
    if (raw & kIdFlagBits)
      return fail(reason, "identifier " + quoted(cs.substr(0, 8)) + " has EFF/RTR flag bits set");
    if (raw & kErrFlag) {
      out.error = true;
      out.id = raw & kEffMask;
    } else {
      out.extended = true;
      out.id = raw;
    }
  }

  size_t i = hash + 1;
  if (i < cs.size() && (cs[i] == 'R' || cs[i] == 'r')) {
    if (out.error) return fail(reason, "an error frame cannot be a remote request");
    out.rtr = true;
    ++i;
    if (i < cs.size()) {
      const int n = nibble(cs[i]);
      if (n < 0 || n > kMaxClassicLen) return fail(reason, "bad remote request length " + quoted(cs.substr(i)));
      out.dlc = static_cast<uint8_t>(n);
      ++i;
      if (i < cs.size() && cs[i] == '_') {
        const int raw_dlc = i + 1 < cs.size() ? nibble(cs[i + 1]) : -1;
        if (out.dlc != 8 || raw_dlc <= 8) return fail(reason, "bad raw DLC " + quoted(cs.substr(i)));
        out.len8_dlc = static_cast<uint8_t>(raw_dlc);
        i += 2;
      }
    }
    if (i != cs.size()) return fail(reason, "unexpected text after remote request: " + quoted(cs.substr(i)));
    return true;
  }

  size_t max_len = kMaxClassicLen;
  if (i < cs.size() && cs[i] == '#') {
    if (out.error) return fail(reason, "an error frame cannot be a CAN FD frame");
    const int flags = i + 1 < cs.size() ? nibble(cs[i + 1]) : -1;
    if (flags < 0) return fail(reason, "CAN FD frame needs a flags hex digit after '##'");
    out.fd = true;
    out.fd_flags = static_cast<uint8_t>(flags);
    max_len = kMaxFdLen;
    i += 2;
  }

  size_t len = 0;
  while (i < cs.size()) {
    if (cs[i] == '.') {  // optional separator, as can-utils accepts
      ++i;
      continue;
    }
    if (cs[i] == '_') break;
    const int hi = nibble(cs[i]);
    if (hi < 0) return fail(reason, "bad hex digit in data " + quoted(cs.substr(i)));
    if (i + 1 >= cs.size()) return fail(reason, "odd number of hex digits in data");
    const int lo = nibble(cs[i + 1]);
    if (lo < 0) return fail(reason, "bad hex digit in data " + quoted(cs.substr(i)));
    if (len == max_len)
      return fail(reason, std::string(out.fd ? "CAN FD" : "classic CAN") + " data longer than " +
                              std::to_string(max_len) + " bytes");
    out.data[len++] = static_cast<uint8_t>(hi << 4 | lo);
    i += 2;
  }
  if (i < cs.size()) {  // '_' raw DLC suffix
    const int raw_dlc = i + 1 < cs.size() ? nibble(cs[i + 1]) : -1;
    if (out.fd || len != 8 || raw_dlc <= 8 || i + 2 != cs.size())
      return fail(reason, "bad raw DLC suffix " + quoted(cs.substr(i)));
    out.len8_dlc = static_cast<uint8_t>(raw_dlc);
  }
  if (out.fd && !isFdLength(static_cast<unsigned>(len)))
    return fail(reason, "CAN FD frames cannot carry " + std::to_string(len) + " bytes");
  out.dlc = static_cast<uint8_t>(len);
  return true;
}

bool parseLine(std::string_view line, Record& out, std::string& reason) {
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t')) line.remove_suffix(1);
  if (line.empty() || line[0] != '(') return fail(reason, "line does not start with '(' timestamp");
  const size_t close = line.find(')');
  if (close == std::string_view::npos) return fail(reason, "timestamp has no closing ')'");
  const std::string_view ts = line.substr(1, close - 1);
  const size_t dot = ts.find('.');
  if (dot == std::string_view::npos || dot == 0 || dot + 1 == ts.size())
    return fail(reason, "timestamp " + quoted(ts) + " is not SECONDS.FRACTION");
  if (dot > 18) return fail(reason, "timestamp " + quoted(ts) + " is too large");
  if (ts.size() - dot - 1 > 9) return fail(reason, "timestamp " + quoted(ts) + " has more than 9 fraction digits");
  int64_t sec = 0;
  for (size_t k = 0; k < dot; ++k) {
    if (ts[k] < '0' || ts[k] > '9') return fail(reason, "bad digit in timestamp " + quoted(ts));
    sec = sec * 10 + (ts[k] - '0');
  }
  uint32_t frac = 0;
  for (size_t k = dot + 1; k < ts.size(); ++k) {
    if (ts[k] < '0' || ts[k] > '9') return fail(reason, "bad digit in timestamp " + quoted(ts));
    frac = frac * 10 + static_cast<uint32_t>(ts[k] - '0');
  }

  // " iface frame [R|T]"; candump right-aligns the interface when it logs several.
  size_t p = close + 1;
  if (p >= line.size() || line[p] != ' ') return fail(reason, "expected a space after the timestamp");
  ++p;
  const size_t col = p;
  while (p < line.size() && line[p] == ' ') ++p;
  const size_t name_begin = p;
  while (p < line.size() && line[p] != ' ' && line[p] != '\t') ++p;
  if (p == name_begin) return fail(reason, "no interface name after the timestamp");
  const std::string_view iface = line.substr(name_begin, p - name_begin);
  if (iface.size() > 64) return fail(reason, "interface name longer than 64 characters");
  const size_t iface_width = name_begin > col ? p - col : 0;  // padded: keep the column width
  if (iface_width > 255) return fail(reason, "interface column wider than 255 characters");
  if (p >= line.size()) return fail(reason, "no frame after interface " + quoted(iface));
  if (line[p] != ' ') return fail(reason, "expected one space after interface " + quoted(iface));
  ++p;
  const size_t frame_begin = p;
  while (p < line.size() && line[p] != ' ') ++p;
  const std::string_view frame_text = line.substr(frame_begin, p - frame_begin);
  char direction = 0;
  if (p < line.size()) {
    const std::string_view rest = line.substr(p);
    if (rest == " R" || rest == " T")
      direction = rest[1];
    else
      return fail(reason, "unexpected text after the frame: " + quoted(rest));
  }

  if (!parseFrame(frame_text, out.frame, reason)) return false;
  static constexpr double kPow10[] = {1, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9};
  const unsigned digits = static_cast<unsigned>(ts.size() - dot - 1);
  out.sec = sec;
  out.frac = frac;
  out.frac_digits = static_cast<uint8_t>(digits);
  out.sec_width = static_cast<uint8_t>(dot);
  out.iface_width = static_cast<uint8_t>(iface_width);
  out.direction = direction;
  out.frame.t = static_cast<double>(sec) + static_cast<double>(frac) / kPow10[digits];
  out.frame.iface.assign(iface);
  return true;
}

std::string formatFrame(const Frame& f) {
  std::string s;
  s.reserve(16 + 2 * f.dlc);
  if (f.error) {
    putHex(s, (f.id & kEffMask) | kErrFlag, 8);
  } else if (f.extended) {
    putHex(s, f.id & kEffMask, 8);
  } else {
    putHex(s, f.id & kSffMask, 3);
  }
  s.push_back('#');
  if (f.rtr && !f.fd && !f.error) {
    s.push_back('R');
    if (f.dlc && f.dlc <= kMaxClassicLen) {
      s.push_back(kHex[f.dlc]);
      if (f.dlc == kMaxClassicLen && f.len8_dlc > 8 && f.len8_dlc <= 15) {
        s.push_back('_');
        s.push_back(kHex[f.len8_dlc]);
      }
    }
    return s;
  }
  const unsigned len = f.dlc <= (f.fd ? kMaxFdLen : kMaxClassicLen) ? f.dlc : (f.fd ? kMaxFdLen : kMaxClassicLen);
  if (f.fd) {
    s.push_back('#');
    s.push_back(kHex[f.fd_flags & 0xF]);
  }
  for (unsigned i = 0; i < len; ++i) putHex(s, f.data[i], 2);
  if (!f.fd && len == kMaxClassicLen && f.len8_dlc > 8 && f.len8_dlc <= 15) {
    s.push_back('_');
    s.push_back(kHex[f.len8_dlc]);
  }
  return s;
}

std::string formatLine(const Record& r) {
  std::string s;
  s.reserve(64 + 2 * r.frame.dlc);
  putStamp(s, r.sec, r.frac, r.frac_digits ? r.frac_digits : 6, r.sec_width);
  s.push_back(' ');
  putPadded(s, r.frame.iface.empty() ? std::string_view("can0") : std::string_view(r.frame.iface), r.iface_width);
  s.push_back(' ');
  s += formatFrame(r.frame);
  if (r.direction == 'R' || r.direction == 'T') {
    s.push_back(' ');
    s.push_back(r.direction);
  }
  return s;
}

std::string formatLine(const Frame& f, std::string_view default_iface) {
  Record r;
  double whole = std::floor(f.t);
  double usec = std::round((f.t - whole) * 1e6);
  if (usec >= 1e6) {
    whole += 1;
    usec -= 1e6;
  }
  r.sec = static_cast<int64_t>(whole);
  r.frac = static_cast<uint32_t>(usec);
  std::string s;
  putStamp(s, r.sec, r.frac, 6, 10);
  s.push_back(' ');
  s.append(f.iface.empty() ? default_iface : std::string_view(f.iface));
  s.push_back(' ');
  s += formatFrame(f);
  return s;
}

// ---- reader ------------------------------------------------------------------

blvd_status CandumpReader::open(const std::string& path) {
  auto f = std::make_unique<std::ifstream>(path, std::ios::binary);
  if (!f->is_open()) {
    error_ = path + ": cannot open: " + std::strerror(errno);
    return BLVD_ERR_IO;
  }
  file_ = std::move(f);
  attach(*file_, path);
  return BLVD_OK;
}

void CandumpReader::attach(std::istream& in, std::string name) {
  in_ = &in;
  name_ = std::move(name);
  buf_.resize(64 * 1024);
  pos_ = end_ = 0;
  eof_ = false;
  line_ = frames_ = bad_lines_ = 0;
  error_.clear();
}

bool CandumpReader::fill() {
  if (eof_ || !in_) return false;
  if (pos_ > 0) {
    std::memmove(buf_.data(), buf_.data() + pos_, end_ - pos_);
    end_ -= pos_;
    pos_ = 0;
  }
  const std::streamsize n =
      in_->rdbuf() ? in_->rdbuf()->sgetn(buf_.data() + end_, static_cast<std::streamsize>(buf_.size() - end_)) : 0;
  if (n <= 0) {
    eof_ = true;
    return false;
  }
  end_ += static_cast<size_t>(n);
  return true;
}

bool CandumpReader::readLine() {
  line_buf_.clear();
  too_long_ = false;
  for (;;) {
    const char* start = buf_.data() + pos_;
    const void* nl = std::memchr(start, '\n', end_ - pos_);
    const size_t take = nl ? static_cast<size_t>(static_cast<const char*>(nl) - start) : end_ - pos_;
    if (!too_long_) {
      if (line_buf_.size() + take > kMaxLine) {
        too_long_ = true;
        line_buf_.clear();
      } else {
        line_buf_.append(start, take);
      }
    }
    if (nl) {
      pos_ += take + 1;
      return true;
    }
    const bool had_data = end_ > pos_ || !line_buf_.empty() || too_long_;
    pos_ = end_;
    if (!fill()) return had_data;  // last line without '\n'
  }
}

CandumpReader::Result CandumpReader::next(Record& out) {
  if (!in_) {
    error_ = "candump reader: no input (call open() or attach())";
    return Result::IoError;
  }
  for (;;) {
    if (!readLine()) {
      if (in_->bad()) {
        error_ = name_ + ":" + std::to_string(line_) + ": read error";
        return Result::IoError;
      }
      return Result::End;
    }
    ++line_;
    if (too_long_) {
      ++bad_lines_;
      error_ = name_ + ":" + std::to_string(line_) + ": line longer than " + std::to_string(kMaxLine) + " bytes";
      return Result::BadLine;
    }
    std::string_view l(line_buf_);
    size_t k = 0;
    while (k < l.size() && (l[k] == ' ' || l[k] == '\t' || l[k] == '\r')) ++k;
    if (k == l.size()) continue;  // blank line
    std::string reason;
    if (!parseLine(l, out, reason)) {
      ++bad_lines_;
      error_ = name_ + ":" + std::to_string(line_) + ": " + reason;
      return Result::BadLine;
    }
    out.line = line_;
    ++frames_;
    return Result::Frame;
  }
}

// ---- writer ------------------------------------------------------------------

blvd_status CandumpWriter::open(const std::string& path, std::string& err) {
  auto f = std::make_unique<std::ofstream>(path, std::ios::binary | std::ios::trunc);
  if (!f->is_open()) {
    err = path + ": cannot create: " + std::strerror(errno);
    return BLVD_ERR_IO;
  }
  file_ = std::move(f);
  out_ = file_.get();
  return BLVD_OK;
}

bool CandumpWriter::write(const Record& r) {
  if (!out_) return false;
  const std::string s = formatLine(r);
  out_->write(s.data(), static_cast<std::streamsize>(s.size()));
  out_->put('\n');
  return static_cast<bool>(*out_);
}

bool CandumpWriter::write(const Frame& f) {
  if (!out_) return false;
  const std::string s = formatLine(f, default_iface);
  out_->write(s.data(), static_cast<std::streamsize>(s.size()));
  out_->put('\n');
  return static_cast<bool>(*out_);
}

bool CandumpWriter::flush() {
  if (!out_) return false;
  out_->flush();
  return static_cast<bool>(*out_);
}

}  // namespace blvd::can
