#include "gnss/nmea.h"

#include <charconv>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <limits>

namespace blvd::gnss {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kKnotsToMps = 1852.0 / 3600.0;
// No NMEA field holds a number this large (a fix stores floats; a speed or
// precision past it is garbage, not a value).
constexpr double kMaxNumber = 1e9;
constexpr double kKphToMps = 1.0 / 3.6;

bool isHex(char c) { return (c >= '0' && c <= '9') || (c >= 'A' && c <= 'F') || (c >= 'a' && c <= 'f'); }
int hexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return c - 'a' + 10;
}

void copyAddress(char (&dst)[9], std::string_view a) {
  const size_t n = a.size() < 8 ? a.size() : 8;
  if (n > 0) std::memcpy(dst, a.data(), n);
  dst[n] = '\0';
}

// Printable preview of some bytes for messages: non-printables as \xNN.
void preview(char* out, size_t cap, const char* data, size_t n) {
  size_t o = 0;
  for (size_t i = 0; i < n && o + 5 < cap; ++i) {
    const auto c = static_cast<unsigned char>(data[i]);
    if (c >= 0x20 && c < 0x7f && c != '\\') {
      out[o++] = static_cast<char>(c);
    } else {
      o += static_cast<size_t>(std::snprintf(out + o, cap - o, "\\x%02X", c));
    }
  }
  out[o < cap ? o : cap - 1] = '\0';
}

}  // namespace

const char* nmeaErrorString(NmeaError e) {
  switch (e) {
    case NmeaError::None: return "no error";
    case NmeaError::Garbage: return "garbage between sentences";
    case NmeaError::BadByte: return "invalid byte in sentence";
    case NmeaError::Overlong: return "overlong sentence";
    case NmeaError::Truncated: return "truncated sentence";
    case NmeaError::BadAddress: return "bad address field";
    case NmeaError::BadChecksum: return "bad checksum";
    case NmeaError::MalformedChecksum: return "malformed checksum";
    case NmeaError::MissingChecksum: return "missing checksum";
    case NmeaError::TooManyFields: return "too many fields";
    case NmeaError::TooFewFields: return "too few fields";
    case NmeaError::BadField: return "malformed field";
  }
  return "unknown error";
}

// ===========================================================================
// SentenceReader

SentenceReader::SentenceReader(const Options& opt) : opt_(opt) {
  if (opt_.max_sentence < 8) opt_.max_sentence = 8;
  if (opt_.max_sentence > buf_.size() - 1) opt_.max_sentence = buf_.size() - 1;
}

void SentenceReader::reset() {
  const Options o = opt_;
  *this = SentenceReader(o);
}

void SentenceReader::report(Handler& h, NmeaError code, uint64_t line, uint64_t offset, std::string_view address,
                            const char* fmt, ...) {
  diag_.code = code;
  diag_.line = line;
  diag_.offset = offset;
  copyAddress(diag_.address, address);
  char reason[160];
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(reason, sizeof reason, fmt, ap);
  va_end(ap);
  if (address.empty())
    std::snprintf(diag_.message, sizeof diag_.message, "line %llu, byte %llu: %s: %s",
                  static_cast<unsigned long long>(line), static_cast<unsigned long long>(offset),
                  nmeaErrorString(code), reason);
  else
    std::snprintf(diag_.message, sizeof diag_.message, "line %llu, byte %llu: %s: %s: %s",
                  static_cast<unsigned long long>(line), static_cast<unsigned long long>(offset), diag_.address,
                  nmeaErrorString(code), reason);
  ++stats_.diagnostics;
  h.onDiagnostic(diag_);
}

void SentenceReader::flushGarbage(Handler& h) {
  if (garbage_count_ == 0) return;
  char p[sizeof garbage_preview_ * 4 + 8];
  preview(p, sizeof p, garbage_preview_.data(), garbage_preview_len_);
  report(h, NmeaError::Garbage, garbage_line_, garbage_offset_, {}, "%llu byte%s not in any sentence: \"%s%s\"",
         static_cast<unsigned long long>(garbage_count_), garbage_count_ == 1 ? "" : "s", p,
         garbage_count_ > garbage_preview_len_ ? "..." : "");
  garbage_count_ = 0;
  garbage_preview_len_ = 0;
}

void SentenceReader::startSentence() {
  state_ = State::Sentence;
  sent_line_ = line_;
  sent_offset_ = offset_;
  len_ = 0;
}

void SentenceReader::feed(const void* data, size_t size, Handler& h) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < size; ++i, ++offset_) {
    const unsigned char c = p[i];
    ++stats_.bytes;
    const bool line_end = (c == '\n' || c == '\r');
    switch (state_) {
      case State::Ground:
      case State::Garbage:
        if (c == '$' || c == '!') {
          flushGarbage(h);
          startSentence();
          buf_[len_++] = static_cast<char>(c);
        } else if (line_end || c == ' ' || c == '\t') {
          if (state_ == State::Garbage && c == '\n') {
            flushGarbage(h);
            state_ = State::Ground;
          }
        } else if (c == '#' && at_line_start_ && opt_.skip_hash_comments && state_ == State::Ground) {
          state_ = State::Comment;
        } else {
          if (garbage_count_ == 0) {
            garbage_line_ = line_;
            garbage_offset_ = offset_;
          }
          if (garbage_preview_len_ < garbage_preview_.size()) garbage_preview_[garbage_preview_len_++] = static_cast<char>(c);
          ++garbage_count_;
          state_ = State::Garbage;
        }
        break;
      case State::Comment:
        if (line_end) state_ = State::Ground;
        break;
      case State::Skip:
        // The rest of a rejected sentence: drop silently up to its line end or the next sentence.
        if (c == '$' || c == '!') {
          startSentence();
          buf_[len_++] = static_cast<char>(c);
        } else if (line_end) {
          state_ = State::Ground;
        }
        break;
      case State::Sentence:
        if (line_end) {
          complete(h, false);
          state_ = State::Ground;
        } else if (c == '$' || c == '!') {
          // A new sentence starts before this one ended. If this one is complete up to
          // a valid checksum only its CR LF was lost (gp-320fw does this): keep it.
          complete(h, true);
          startSentence();
          buf_[len_++] = static_cast<char>(c);
        } else if (c < 0x20 || c > 0x7e) {
          char shown[48];
          preview(shown, sizeof shown, buf_.data(), len_ < 12 ? len_ : 12);
          const size_t addr_end = std::string_view(buf_.data(), len_).find_first_of(",*");
          report(h, NmeaError::BadByte, sent_line_, sent_offset_,
                 std::string_view(buf_.data() + 1, (addr_end == std::string_view::npos ? len_ : addr_end) - 1),
                 "byte 0x%02X at column %zu (\"%s...\"); sentence dropped", c, len_ + 1, shown);
          state_ = State::Skip;
        } else if (len_ >= opt_.max_sentence) {
          char shown[48];
          preview(shown, sizeof shown, buf_.data(), 16);
          report(h, NmeaError::Overlong, sent_line_, sent_offset_, {},
                 "no line end within %zu bytes (\"%s...\"); skipped to the next sentence", opt_.max_sentence, shown);
          state_ = State::Skip;
        } else {
          buf_[len_++] = static_cast<char>(c);
        }
        break;
    }
    if (c == '\n') ++line_;
    at_line_start_ = line_end;
  }
}

void SentenceReader::finish(Handler& h) {
  if (state_ == State::Sentence) complete(h, true);
  flushGarbage(h);
  state_ = State::Ground;
}

// `cut`: the sentence ended without CR/LF (a '$' followed, or the input ended).
void SentenceReader::complete(Handler& h, bool cut) {
  const std::string_view text(buf_.data(), len_);
  Sentence& s = sentence_;
  s.text = text;
  s.line = sent_line_;
  s.offset = sent_offset_;

  // Checksum: the last '*' must be followed by exactly two hex digits.
  const size_t star = text.rfind('*');
  const size_t body_end = star == std::string_view::npos ? text.size() : star;
  const std::string_view body = text.substr(1, body_end - 1);
  const size_t comma = body.find(',');
  const std::string_view address = body.substr(0, comma == std::string_view::npos ? body.size() : comma);

  char shown[64];
  if (cut) {
    const bool complete_sum = star != std::string_view::npos && text.size() == star + 3 && isHex(text[star + 1]) &&
                              isHex(text[star + 2]);
    if (!complete_sum) {
      preview(shown, sizeof shown, text.data(), text.size() < 40 ? text.size() : 40);
      report(h, NmeaError::Truncated, s.line, s.offset, address, "sentence cut off after %zu bytes (\"%s%s\")",
             text.size(), shown, text.size() > 40 ? "..." : "");
      return;
    }
  }
  // Address: 3..8 upper-case letters/digits ("GPGGA", "PSRFEPE", "PSTI", SkyTraq's "STI").
  bool addr_ok = address.size() >= 3 && address.size() <= 8;
  for (const char ch : address)
    if (!((ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9'))) addr_ok = false;
  if (!addr_ok) {
    preview(shown, sizeof shown, text.data(), text.size() < 40 ? text.size() : 40);
    report(h, NmeaError::BadAddress, s.line, s.offset, {}, "\"%s%s\"", shown, text.size() > 40 ? "..." : "");
    return;
  }
  if (star != std::string_view::npos) {
    if (text.size() != star + 3 || !isHex(text[star + 1]) || !isHex(text[star + 2])) {
      preview(shown, sizeof shown, text.data() + star, text.size() - star < 16 ? text.size() - star : 16);
      report(h, NmeaError::MalformedChecksum, s.line, s.offset, address,
             "expected '*' and two hex digits at the end, found \"%s\"", shown);
      return;
    }
    unsigned sum = 0;
    for (const char ch : body) sum ^= static_cast<unsigned char>(ch);
    const unsigned given = static_cast<unsigned>(hexValue(text[star + 1]) * 16 + hexValue(text[star + 2]));
    if (sum != given) {
      ++stats_.bad_checksum;
      report(h, NmeaError::BadChecksum, s.line, s.offset, address, "sentence says *%02X, its bytes give *%02X", given,
             sum);
      return;
    }
    s.has_checksum = true;
  } else {
    if (opt_.require_checksum) {
      report(h, NmeaError::MissingChecksum, s.line, s.offset, address, "no '*hh' at the end of the sentence");
      return;
    }
    s.has_checksum = false;
  }

  // Fields.
  size_t n = 0;
  size_t start = 0;
  while (true) {
    const size_t next = body.find(',', start);
    const std::string_view f = body.substr(start, next == std::string_view::npos ? std::string_view::npos : next - start);
    if (n > Sentence::kMaxFields) {
      report(h, NmeaError::TooManyFields, s.line, s.offset, address, "more than %zu fields", Sentence::kMaxFields);
      return;
    }
    s.fields[n++] = f;
    if (next == std::string_view::npos) break;
    start = next + 1;
  }
  s.field_count = n - 1;
  s.address = address;
  s.proprietary = address[0] == 'P';
  if (s.proprietary) {
    s.talker = {};
    s.type = address.substr(1);
  } else {
    s.talker = address.substr(0, 2);
    s.type = address.substr(2);
  }
  ++stats_.sentences;
  if (!s.has_checksum) ++stats_.no_checksum;
  h.onSentence(s);
}

// ===========================================================================
// decodeSentence

bool isGnssTalker(std::string_view t) {
  return t == "GP" || t == "GN" || t == "GL" || t == "GA" || t == "GB" || t == "BD" || t == "GQ" || t == "GI" ||
         t == "QZ";
}

SentenceType sentenceType(std::string_view t) {
  if (t == "RMC") return SentenceType::RMC;
  if (t == "GGA") return SentenceType::GGA;
  if (t == "GNS") return SentenceType::GNS;
  if (t == "VTG") return SentenceType::VTG;
  if (t == "GSA") return SentenceType::GSA;
  if (t == "GST") return SentenceType::GST;
  if (t == "GLL") return SentenceType::GLL;
  if (t == "ZDA") return SentenceType::ZDA;
  if (t == "HDT") return SentenceType::HDT;
  if (t == "THS") return SentenceType::THS;
  return SentenceType::Unknown;
}

namespace {

// Field parsing: each returns false on a malformed (non-empty) field and sets
// `why`; an empty field leaves the output at "absent" and returns true.
struct FieldReader {
  const Sentence& s;
  NmeaDiagnostic* diag;
  bool ok = true;

  void fail(size_t i, const char* what, const char* why) {
    if (!ok) return;  // first problem wins
    ok = false;
    if (!diag) return;
    diag->code = NmeaError::BadField;
    diag->line = s.line;
    diag->offset = s.offset;
    copyAddress(diag->address, s.address);
    char v[40];
    const std::string_view f = s.field(i);
    preview(v, sizeof v, f.data(), f.size() < 20 ? f.size() : 20);
    std::snprintf(diag->message, sizeof diag->message, "line %llu, byte %llu: %s: malformed field: field %zu (%s) \"%s\": %s",
                  static_cast<unsigned long long>(s.line), static_cast<unsigned long long>(s.offset), diag->address, i,
                  what, v, why);
  }

  // Plain decimal number ("12.5", "-3", ".5"); leading '+' allowed.
  double number(size_t i, const char* what) {
    std::string_view f = s.field(i);
    if (f.empty()) return kNaN;
    if (f[0] == '+') f.remove_prefix(1);
    double v = 0;
    const auto r = std::from_chars(f.data(), f.data() + f.size(), v, std::chars_format::fixed);
    if (r.ec != std::errc() || r.ptr != f.data() + f.size() || !std::isfinite(v)) {
      fail(i, what, "not a decimal number");
      return kNaN;
    }
    if (std::fabs(v) > kMaxNumber) {  // a fix's fields are floats: 1e39 knots would become inf
      fail(i, what, "out of range");
      return kNaN;
    }
    return v;
  }
  // The same within [lo, hi].
  double number(size_t i, const char* what, double lo, double hi) {
    const double v = number(i, what);
    if (std::isnan(v) || (v >= lo && v <= hi)) return v;
    fail(i, what, "out of range");
    return kNaN;
  }

  int integer(size_t i, const char* what, int lo, int hi) {
    const std::string_view f = s.field(i);
    if (f.empty()) return -1;
    int v = 0;
    const auto r = std::from_chars(f.data(), f.data() + f.size(), v);
    if (r.ec != std::errc() || r.ptr != f.data() + f.size()) {
      fail(i, what, "not an integer");
      return -1;
    }
    if (v < lo || v > hi) {
      fail(i, what, "out of range");
      return -1;
    }
    return v;
  }

  char letter(size_t i, const char* what, const char* allowed) {
    const std::string_view f = s.field(i);
    if (f.empty()) return '\0';
    if (f.size() != 1 || !std::strchr(allowed, f[0])) {
      fail(i, what, "unexpected value");
      return '\0';
    }
    return f[0];
  }

  // hhmmss[.s+] -> ms since midnight. false if empty.
  bool time(size_t i, int64_t* ms) {
    const std::string_view f = s.field(i);
    if (f.empty()) return false;
    bool good = f.size() >= 6;
    for (size_t k = 0; good && k < 6; ++k) good = f[k] >= '0' && f[k] <= '9';
    if (good && f.size() > 6) {
      good = f[6] == '.';
      for (size_t k = 7; good && k < f.size(); ++k) good = f[k] >= '0' && f[k] <= '9';
    }
    if (!good) {
      fail(i, "time", "expected hhmmss or hhmmss.ss");
      return false;
    }
    const int hh = (f[0] - '0') * 10 + (f[1] - '0');
    const int mm = (f[2] - '0') * 10 + (f[3] - '0');
    const int ss = (f[4] - '0') * 10 + (f[5] - '0');
    if (hh > 23 || mm > 59 || ss > 60) {
      fail(i, "time", "hour, minute or second out of range");
      return false;
    }
    // Fraction, rounded to ms (integer arithmetic: no float drift in epoch keys).
    int64_t frac_ms = 0;
    if (f.size() > 7) {
      int64_t num = 0;
      int digits = 0;
      for (size_t k = 7; k < f.size() && digits < 9; ++k, ++digits) num = num * 10 + (f[k] - '0');
      int64_t den = 1;
      for (int k = 0; k < digits; ++k) den *= 10;
      frac_ms = (num * 1000 + den / 2) / den;
    }
    *ms = (static_cast<int64_t>(hh) * 3600 + mm * 60 + ss) * 1000 + frac_ms;
    return true;
  }

  // [d]ddmm.mmmm + hemisphere -> degrees. Returns false if either field is empty.
  bool coordinate(size_t i, size_t hemi_i, bool is_lat, double* out) {
    const std::string_view f = s.field(i);
    const std::string_view h = s.field(hemi_i);
    if (f.empty() || h.empty()) return false;
    const char* name = is_lat ? "latitude" : "longitude";
    const size_t dot = f.find('.');
    const size_t int_len = dot == std::string_view::npos ? f.size() : dot;
    bool good = int_len >= 3 && int_len <= (is_lat ? 4u : 5u);
    for (size_t k = 0; good && k < f.size(); ++k) good = (f[k] >= '0' && f[k] <= '9') || k == dot;
    if (!good) {
      fail(i, name, is_lat ? "expected ddmm.mmmm" : "expected dddmm.mmmm");
      return false;
    }
    int deg = 0;
    for (size_t k = 0; k < int_len - 2; ++k) deg = deg * 10 + (f[k] - '0');
    double minutes = 0;
    const char* mstart = f.data() + int_len - 2;
    const auto r = std::from_chars(mstart, f.data() + f.size(), minutes, std::chars_format::fixed);
    if (r.ec != std::errc() || minutes >= 60.0 || deg > (is_lat ? 90 : 180)) {
      fail(i, name, "degrees or minutes out of range");
      return false;
    }
    double v = deg + minutes / 60.0;
    const char hc = h.size() == 1 ? h[0] : '?';
    if (is_lat ? (hc != 'N' && hc != 'S') : (hc != 'E' && hc != 'W')) {
      fail(hemi_i, is_lat ? "N/S" : "E/W", "unexpected hemisphere");
      return false;
    }
    if (hc == 'S' || hc == 'W') v = -v;
    if (std::fabs(v) > (is_lat ? 90.0 : 180.0)) {
      fail(i, name, "out of range");
      return false;
    }
    *out = v;
    return true;
  }

  bool position(size_t lat_i, double* lat, double* lon) {
    double a = 0, b = 0;
    const bool has_a = coordinate(lat_i, lat_i + 1, true, &a);
    const bool has_b = coordinate(lat_i + 2, lat_i + 3, false, &b);
    if (!has_a || !has_b) return false;
    *lat = a;
    *lon = b;
    return true;
  }
};

// Mode and navigational-status indicators: NMEA defines A D E F M N P R S
// (and S C U V for navigational status), vendors add their own (Quectel: C,
// U in RMC), so any letter is taken; unknown ones read as plain GPS.
constexpr const char* kModeLetters = "ABCDEFGHIJKLMNOPQRSTUVWXYZ";

// Minimum field counts: what the sentence must have for the fields we read
// to be where we read them (trailing optional fields may be missing).
size_t minFields(SentenceType t) {
  switch (t) {
    case SentenceType::RMC: return 9;   // ...,date
    case SentenceType::GGA: return 9;   // ...,altitude
    case SentenceType::GNS: return 9;   // ...,altitude
    case SentenceType::VTG: return 4;   // old form: track,speed knots,...
    case SentenceType::GSA: return 2;   // mode letter, fix type (DOPs may be missing)
    case SentenceType::GST: return 8;
    case SentenceType::GLL: return 4;   // lat,N,lon,E (time, status: NMEA 2.0 and later)
    case SentenceType::ZDA: return 4;
    case SentenceType::HDT: return 1;
    case SentenceType::THS: return 2;
    case SentenceType::Unknown: return 0;
  }
  return 0;
}

int statusFromFaa(char faa, int fallback) {
  switch (faa) {
    case 'A': return kStatusGps;
    case 'D': return kStatusDgps;
    case 'P': return kStatusDgps;
    case 'R': return kStatusRtkFixed;
    case 'F': return kStatusRtkFloat;
    case 'E': return kStatusDeadReckoning;
    case 'M': return kStatusManual;
    case 'S': return kStatusSimulated;
    default: return fallback;
  }
}

}  // namespace

namespace {

// RMC,hhmmss,status,lat,N,lon,E,knots,track,ddmmyy,magvar,E/W[,faa[,navstatus]]
void decodeRmc(FieldReader& f, NmeaRecord& r) {
  const Sentence& s = f.s;
  r.has_tod = f.time(1, &r.tod_ms);
  r.status = f.letter(2, "status", "AVD");
  r.has_pos = f.position(3, &r.lat, &r.lon);
  r.speed_mps = f.number(7, "speed") * kKnotsToMps;
  r.track_deg = f.number(8, "track", 0, 360);
  const std::string_view d = s.field(9);
  if (!d.empty()) {
    bool good = d.size() == 6;
    for (size_t k = 0; good && k < 6; ++k) good = d[k] >= '0' && d[k] <= '9';
    if (!good) {
      f.fail(9, "date", "expected ddmmyy");
    } else {
      r.day = (d[0] - '0') * 10 + (d[1] - '0');
      r.month = (d[2] - '0') * 10 + (d[3] - '0');
      const int yy = (d[4] - '0') * 10 + (d[5] - '0');
      // Two-digit years: 1980..2079, as gpsd (GPS time starts in 1980).
      r.year = yy < 80 ? 2000 + yy : 1900 + yy;
      if (r.month < 1 || r.month > 12 || r.day < 1 || r.day > 31)
        f.fail(9, "date", "day or month out of range");
      else
        r.has_date = true;
    }
  }
  if (s.field_count >= 12) r.faa = f.letter(12, "mode", kModeLetters);
  if (s.field_count >= 13) r.nav_status = f.letter(13, "navigational status", kModeLetters);
}

// GGA,hhmmss,lat,N,lon,E,quality,sats,hdop,alt,M,geoid,M,age,station
void decodeGga(FieldReader& f, NmeaRecord& r) {
  r.has_tod = f.time(1, &r.tod_ms);
  r.has_pos = f.position(2, &r.lat, &r.lon);
  r.quality = f.integer(6, "quality", 0, 9);
  r.sats = f.integer(7, "satellites", 0, 255);
  r.hdop = f.number(8, "HDOP");
  r.alt = f.number(9, "altitude");
  r.geoid_sep = f.number(11, "geoid separation");
}

// GNS,hhmmss,lat,N,lon,E,modes,sats,hdop,alt,geoid,age,station[,navstatus]
void decodeGns(FieldReader& f, NmeaRecord& r) {
  const Sentence& s = f.s;
  r.has_tod = f.time(1, &r.tod_ms);
  r.has_pos = f.position(2, &r.lat, &r.lon);
  const std::string_view m = s.field(6);
  for (const char ch : m)
    if (ch < 'A' || ch > 'Z') f.fail(6, "mode", "mode indicators must be letters");
  r.faa = m.empty() ? '\0' : m[0];
  r.sats = f.integer(7, "satellites", 0, 255);
  r.hdop = f.number(8, "HDOP");
  r.alt = f.number(9, "altitude");
  r.geoid_sep = f.number(10, "geoid separation");
  if (s.field_count >= 13) r.nav_status = f.letter(13, "navigational status", kModeLetters);
}

// VTG,track,T,magtrack,M,knots,N,kph,K[,faa]; the pre-2.0 form is
// VTG,track,magtrack,knots,kph.
void decodeVtg(FieldReader& f, NmeaRecord& r) {
  const Sentence& s = f.s;
  if (s.field(2) == "T") {
    r.track_deg = f.number(1, "track", 0, 360);
    r.speed_mps = f.number(5, "speed (knots)") * kKnotsToMps;
    if (std::isnan(r.speed_mps)) r.speed_mps = f.number(7, "speed (km/h)") * kKphToMps;
    if (s.field_count >= 9) r.faa = f.letter(9, "mode", kModeLetters);
  } else {
    r.track_deg = f.number(1, "track", 0, 360);
    r.speed_mps = f.number(3, "speed (knots)") * kKnotsToMps;
  }
}

// GSA,A/M,fixtype,sv1..sv12,pdop,hdop,vdop[,systemid]
void decodeGsa(FieldReader& f, NmeaRecord& r) {
  const Sentence& s = f.s;
  r.gsa_mode = f.integer(2, "fix type", 1, 3);
  if (r.gsa_mode < 0) r.gsa_mode = 0;
  if (s.field_count >= 17) {
    r.pdop = f.number(15, "PDOP");
    r.hdop = f.number(16, "HDOP");
    r.vdop = f.number(17, "VDOP");
  }
}

// GST,hhmmss,rms,smajor,sminor,orient,lat_err,lon_err,alt_err
void decodeGst(FieldReader& f, NmeaRecord& r) {
  r.has_tod = f.time(1, &r.tod_ms);
  r.rms = f.number(2, "RMS");
  (void)f.number(3, "semi-major");
  (void)f.number(4, "semi-minor");
  (void)f.number(5, "orientation");
  r.lat_err = f.number(6, "latitude error");
  r.lon_err = f.number(7, "longitude error");
  r.alt_err = f.number(8, "altitude error");
}

// GLL,lat,N,lon,E[,hhmmss,status[,faa]]
void decodeGll(FieldReader& f, NmeaRecord& r) {
  const Sentence& s = f.s;
  r.has_pos = f.position(1, &r.lat, &r.lon);
  r.has_tod = f.time(5, &r.tod_ms);
  r.status = f.letter(6, "status", "AV");
  if (s.field_count >= 7) r.faa = f.letter(7, "mode", kModeLetters);
}

// ZDA,hhmmss,dd,mm,yyyy,zone_h,zone_m
void decodeZda(FieldReader& f, NmeaRecord& r) {
  r.has_tod = f.time(1, &r.tod_ms);
  const int d = f.integer(2, "day", 1, 31);
  const int m = f.integer(3, "month", 1, 12);
  const int y = f.integer(4, "year", 1980, 2200);
  if (d > 0 && m > 0 && y > 0) {
    r.has_date = true;
    r.day = d;
    r.month = m;
    r.year = y;
  }
}

// HDT,heading,T
void decodeHdt(FieldReader& f, NmeaRecord& r) {
  r.heading_deg = f.number(1, "heading");
  if (!std::isnan(r.heading_deg) && (r.heading_deg < 0 || r.heading_deg > 360)) f.fail(1, "heading", "out of range");
}

// THS,heading,mode (A autonomous, E estimated, M manual, S simulator, V invalid)
void decodeThs(FieldReader& f, NmeaRecord& r) {
  r.heading_deg = f.number(1, "heading");
  r.faa = f.letter(2, "mode", kModeLetters);
  if (!std::isnan(r.heading_deg) && (r.heading_deg < 0 || r.heading_deg > 360)) f.fail(1, "heading", "out of range");
}

}  // namespace

bool decodeSentence(const Sentence& s, NmeaRecord* rec, NmeaDiagnostic* diag) {
  if (diag) diag->code = NmeaError::None;
  if (s.proprietary || !isGnssTalker(s.talker)) return false;
  const SentenceType type = sentenceType(s.type);
  if (type == SentenceType::Unknown) return false;

  NmeaRecord r;
  r.type = type;
  r.talker[0] = s.talker[0];
  r.talker[1] = s.talker[1];
  r.line = s.line;
  r.offset = s.offset;
  r.has_checksum = s.has_checksum;
  r.hdop = r.pdop = r.vdop = r.alt = r.geoid_sep = r.speed_mps = r.track_deg = kNaN;
  r.rms = r.lat_err = r.lon_err = r.alt_err = r.heading_deg = kNaN;

  if (s.field_count < minFields(type)) {
    if (diag) {
      diag->code = NmeaError::TooFewFields;
      diag->line = s.line;
      diag->offset = s.offset;
      copyAddress(diag->address, s.address);
      std::snprintf(diag->message, sizeof diag->message, "line %llu, byte %llu: %s: too few fields: %zu, need %zu",
                    static_cast<unsigned long long>(s.line), static_cast<unsigned long long>(s.offset), diag->address,
                    s.field_count, minFields(type));
    }
    return false;
  }

  FieldReader f{s, diag};
  switch (type) {
    case SentenceType::RMC: decodeRmc(f, r); break;
    case SentenceType::GGA: decodeGga(f, r); break;
    case SentenceType::GNS: decodeGns(f, r); break;
    case SentenceType::VTG: decodeVtg(f, r); break;
    case SentenceType::GSA: decodeGsa(f, r); break;
    case SentenceType::GST: decodeGst(f, r); break;
    case SentenceType::GLL: decodeGll(f, r); break;
    case SentenceType::ZDA: decodeZda(f, r); break;
    case SentenceType::HDT: decodeHdt(f, r); break;
    case SentenceType::THS: decodeThs(f, r); break;
    case SentenceType::Unknown: return false;
  }
  if (!f.ok) return false;
  *rec = r;
  return true;
}

// ===========================================================================
// FixAssembler

bool FixAssembler::Key::operator==(const Key& o) const {
  return count == o.count && std::strcmp(address, o.address) == 0;
}

void FixAssembler::reset() {
  cur_ = Epoch{};
  gst_ = Gst{};
  have_date_ = false;
  last_days_ = 0;
  last_tod_ms_ = 0;
  last_gsa_mode_ = 0;
  last_gsa_tod_ms_ = 0;
  seen_n_ = 0;
  last_key_ = Key{};
  ender_ = Key{};
  candidate_ = Key{};
  ender_reliable_ = false;
  emitted_ = false;
}

uint16_t FixAssembler::countOf(std::string_view address) {
  char a[9];
  copyAddress(a, address);
  for (size_t i = 0; i < seen_n_; ++i)
    if (std::strcmp(seen_[i].address, a) == 0) return ++seen_[i].count;
  if (seen_n_ < seen_.size()) {
    std::memcpy(seen_[seen_n_].address, a, sizeof a);
    seen_[seen_n_].count = 1;
    ++seen_n_;
    return 1;
  }
  return 0;  // too many distinct addresses in one epoch: not usable as an ender
}

bool FixAssembler::onePerCycle(SentenceType t) {
  return t == SentenceType::RMC || t == SentenceType::GGA || t == SentenceType::GNS || t == SentenceType::GLL ||
         t == SentenceType::VTG || t == SentenceType::ZDA;
}

bool FixAssembler::reached(const Key& k) const {
  for (size_t i = 0; i < seen_n_; ++i)
    if (std::strcmp(seen_[i].address, k.address) == 0) return seen_[i].count >= k.count;
  return false;
}

bool FixAssembler::seenInEpoch(std::string_view address) const {
  char a[9];
  copyAddress(a, address);
  for (size_t i = 0; i < seen_n_; ++i)
    if (std::strcmp(seen_[i].address, a) == 0) return true;
  return false;
}

void FixAssembler::startEpoch() {
  cur_ = Epoch{};
  cur_.open = true;
  seen_n_ = 0;
  last_key_ = Key{};
  emitted_ = false;
}

void FixAssembler::emit(Handler& h, const Fix& f) { h.onFix(f); }

namespace {
bool same(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }
bool sameFix(const Fix& a, const Fix& b) {
  return same(a.t_unix, b.t_unix) && same(a.lat, b.lat) && same(a.lon, b.lon) && same(a.alt, b.alt) &&
         same(a.speed_mps, b.speed_mps) && same(a.track_deg, b.track_deg) && same(a.hdop, b.hdop) &&
         same(a.h_acc_m, b.h_acc_m) && same(a.v_acc_m, b.v_acc_m) && same(a.lat_err_m, b.lat_err_m) &&
         same(a.lon_err_m, b.lon_err_m) && same(a.heading_deg, b.heading_deg) && same(a.geoid_sep_m, b.geoid_sep_m) &&
         same(a.pdop, b.pdop) && same(a.vdop, b.vdop) && a.mode == b.mode && a.status == b.status &&
         a.sats_used == b.sats_used && a.flags == b.flags;
}
}  // namespace

int FixAssembler::modeOf(const Epoch& e) const {
  int mode = e.alt_3d ? kMode3D : kMode2D;
  if (e.gsa_mode >= 2) {
    if (!(e.gsa_mode == 2 && e.alt_3d)) mode = e.gsa_mode;
  } else if (e.gsa_mode == 0 && last_gsa_mode_ == kMode3D && (e.has_alt || !e.gga_or_gns) && e.has_tod) {
    // No GSA in this epoch (many receivers send it less often than GGA/RMC,
    // or the log ends first): a 3D fix type stated in the last 10 s still
    // holds while the receiver keeps reporting an altitude, or sends no
    // GGA/GNS that could say otherwise (RMC-only epochs).
    int64_t age = e.tod_ms - last_gsa_tod_ms_;
    if (age < 0) age += 24 * 3600 * 1000;
    if (age <= 10 * 1000) mode = kMode3D;
  }
  return mode;
}

void FixAssembler::buildTime(const Epoch& e, Fix& f) const {
  if (!e.has_tod) return;
  int64_t days = 0;
  if (e.has_date) {
    days = e.days;
  } else if (have_date_) {
    days = last_days_;
    if (e.tod_ms + 12 * 3600 * 1000 < last_tod_ms_) days += 1;  // past midnight since the date was learned
  } else {
    return;
  }
  f.t_unix = static_cast<double>(days) * 86400.0 + static_cast<double>(e.tod_ms) / 1000.0;
  f.flags |= kFixHasTime;
}

void FixAssembler::buildErrors(const Epoch& e, Fix& f) const {
  if (!(gst_.valid && e.has_tod && gst_.tod_ms == e.tod_ms)) return;
  if (!std::isnan(gst_.lat_err) && !std::isnan(gst_.lon_err)) {
    f.lat_err_m = static_cast<float>(gst_.lat_err);
    f.lon_err_m = static_cast<float>(gst_.lon_err);
    f.h_acc_m = static_cast<float>(std::sqrt(gst_.lat_err * gst_.lat_err + gst_.lon_err * gst_.lon_err));
    f.flags |= kFixHasHAcc;
  }
  if (!std::isnan(gst_.alt_err)) {
    f.v_acc_m = static_cast<float>(gst_.alt_err);
    f.flags |= kFixHasVAcc;
  }
}

// The fix's position, mode, altitude, status, speed and track: only with a fix.
void FixAssembler::buildPosition(const Epoch& e, Fix& f) const {
  f.lat = e.lat;
  f.lon = e.lon;
  f.flags |= kFixHasLatLon;
  f.mode = modeOf(e);
  if (e.has_alt) {  // in 2D, the altitude the receiver held (gpsd reports it too)
    f.alt = e.alt;
    f.flags |= kFixHasAlt;
  }
  // GGA's quality says most (RTK fixed/float, DGPS, PPS); else the first FAA mode letter.
  f.status = e.gga_status != kStatusUnknown ? e.gga_status : e.faa_status != kStatusUnknown ? e.faa_status : kStatusGps;
  if (e.has_speed) {
    f.speed_mps = static_cast<float>(e.speed);
    f.flags |= kFixHasSpeed;
  }
  if (e.has_track) {
    f.track_deg = static_cast<float>(e.track);
    f.flags |= kFixHasTrack;
  }
  buildErrors(e, f);
}

Fix FixAssembler::build(const Epoch& e) const {
  Fix f = Fix::empty();
  buildTime(e, f);
  if (e.hasFix())
    buildPosition(e, f);
  else if (e.any_position_sentence)
    f.mode = kModeNoFix;
  if (e.has_heading) {
    f.heading_deg = static_cast<float>(e.heading_deg);
    f.flags |= kFixHasHeading;
  }
  if (e.has_hdop) {
    f.hdop = static_cast<float>(e.hdop);
    f.flags |= kFixHasHdop;
  }
  if (e.has_pdop) {
    f.pdop = static_cast<float>(e.pdop);
    f.vdop = static_cast<float>(e.vdop);
    f.flags |= kFixHasPdop;
  }
  if (e.has_geoid) {
    f.geoid_sep_m = static_cast<float>(e.geoid_sep);
    f.flags |= kFixHasGeoidSep;
  }
  f.sats_used = e.sats;
  if (e.no_checksum) f.flags |= kFixNoChecksum;
  return f;
}

// ---- one sentence into the epoch ----------------------------------------------

bool FixAssembler::Epoch::hasFix() const { return any_position_sentence && !invalid && !nofix_vote && has_pos; }

void FixAssembler::Epoch::position(const NmeaRecord& r) {
  if (!r.has_pos) return;
  has_pos = true;
  lat = r.lat;
  lon = r.lon;
}

void FixAssembler::Epoch::motion(const NmeaRecord& r) {
  if (!std::isnan(r.speed_mps)) {
    has_speed = true;
    speed = r.speed_mps;
  }
  if (!std::isnan(r.track_deg)) {
    has_track = true;
    track = r.track_deg;
  }
}

void FixAssembler::Epoch::rmc(const NmeaRecord& r) {
  any_position_sentence = true;
  const bool ok = r.status == 'A' || r.status == 'D';
  if (!ok || r.faa == 'N') {
    invalid = true;
    return;
  }
  nofix_vote = false;
  if (r.has_date) {
    has_date = true;
    days = daysFromCivil(r.year, static_cast<unsigned>(r.month), static_cast<unsigned>(r.day));
  }
  position(r);
  motion(r);
  if (faa_status == kStatusUnknown) faa_status = statusFromFaa(r.faa, r.status == 'D' ? kStatusDgps : kStatusGps);
}

// GGA and GNS carry the same fix fields; both merge them the same way.
void FixAssembler::Epoch::ggaGns(const NmeaRecord& r) {
  gga_or_gns = true;
  nofix_vote = false;
  position(r);
  if (r.sats >= 0) sats = r.sats;
  if (!std::isnan(r.alt)) {
    has_alt = true;
    alt = r.alt;
    alt_3d = alt_3d || r.sats >= 4;
  }
  if (!std::isnan(r.geoid_sep)) {
    has_geoid = true;
    geoid_sep = r.geoid_sep;
  }
  if (!std::isnan(r.hdop) && r.hdop < 99.0) {  // 99.99: "unknown" on BT-451 and others
    has_hdop = true;
    hdop = r.hdop;
  }
}

void FixAssembler::Epoch::gga(const NmeaRecord& r) {
  any_position_sentence = true;
  if (r.quality <= 0) {
    invalid = true;
    return;
  }
  ggaGns(r);
  // gpsd's processGGA: fewer than 3 satellites used (an empty field reads 0) is no fix.
  nofix_vote = r.has_pos && r.sats < 3;
  static constexpr int kQuality[] = {kStatusUnknown,  kStatusGps,      kStatusDgps,          kStatusPps,
                                     kStatusRtkFixed, kStatusRtkFloat, kStatusDeadReckoning, kStatusManual,
                                     kStatusSimulated, kStatusUnknown};
  gga_status = kQuality[r.quality];
}

void FixAssembler::Epoch::gns(const NmeaRecord& r) {
  any_position_sentence = true;
  // FAA mode of the first system ('N': no fix); navigational status U/V: unusable.
  if (r.faa == '\0' || r.faa == 'N') {
    invalid = true;
    return;
  }
  if (r.nav_status == 'U' || r.nav_status == 'V') return;
  ggaGns(r);
  if (faa_status == kStatusUnknown) faa_status = statusFromFaa(r.faa, kStatusGps);
}

void FixAssembler::Epoch::gll(const NmeaRecord& r) {
  any_position_sentence = true;
  if (r.status == 'V' || r.faa == 'N') {
    invalid = true;
    return;
  }
  nofix_vote = false;
  position(r);
}

void FixAssembler::Epoch::gsa(const NmeaRecord& r) {
  if (r.gsa_mode > gsa_mode) gsa_mode = r.gsa_mode;
  if (r.gsa_mode > 0) nofix_vote = r.gsa_mode == kModeNoFix;  // gpsd: the last sentence that states a mode wins
  if (!std::isnan(r.pdop) && r.pdop < 99.0) {
    has_pdop = true;
    pdop = r.pdop;
    vdop = r.vdop;
  }
  if (!std::isnan(r.hdop) && r.hdop < 99.0) {
    has_hdop = true;
    hdop = r.hdop;
  }
}

void FixAssembler::Epoch::date(const NmeaRecord& r) {
  if (!r.has_date) return;
  has_date = true;
  days = daysFromCivil(r.year, static_cast<unsigned>(r.month), static_cast<unsigned>(r.day));
}

void FixAssembler::Epoch::heading(const NmeaRecord& r) {
  if (r.type == SentenceType::THS && r.faa == 'V') return;
  if (std::isnan(r.heading_deg)) return;
  has_heading = true;
  heading_deg = r.heading_deg;
}

void FixAssembler::applyGst(const NmeaRecord& r) {
  if (!r.has_tod) return;
  gst_.valid = true;
  gst_.tod_ms = r.tod_ms;
  gst_.lat_err = r.lat_err;
  gst_.lon_err = r.lon_err;
  gst_.alt_err = r.alt_err;
}

void FixAssembler::apply(const NmeaRecord& r) {
  Epoch& e = cur_;
  if (!r.has_checksum) e.no_checksum = true;
  if (r.has_tod && !e.has_tod && r.type != SentenceType::GST) {
    e.has_tod = true;
    e.tod_ms = r.tod_ms;
  }
  switch (r.type) {
    case SentenceType::RMC: e.rmc(r); break;
    case SentenceType::GGA: e.gga(r); break;
    case SentenceType::GNS: e.gns(r); break;
    case SentenceType::GLL: e.gll(r); break;
    case SentenceType::VTG:
      if (r.faa != 'N' && r.faa != 'E') e.motion(r);  // not valid / dead reckoning only
      break;
    case SentenceType::GSA: e.gsa(r); break;
    case SentenceType::GST: applyGst(r); break;
    case SentenceType::ZDA: e.date(r); break;
    case SentenceType::HDT:
    case SentenceType::THS: e.heading(r); break;
    case SentenceType::Unknown: break;
  }
}

void FixAssembler::closeEpoch(Handler& h, bool learn) {
  if (!cur_.open) return;
  // Learn the cycle ender: the same last decoded sentence at two consecutive
  // closes. Once learned it only moves later in the cycle: to a sentence that
  // came after it in this epoch. An epoch that ends earlier because it lacks the
  // ender (no GST without a fix, a GSA every few cycles) keeps it: such an epoch
  // closes when the next one begins, once, and the next complete epoch is not
  // emitted at a premature ender and again when its last sentences arrive.
  if (learn && last_key_.count > 0) {
    if (ender_reliable_) {
      if (!(last_key_ == ender_) && reached(ender_)) ender_ = last_key_;
    } else if (last_key_ == candidate_) {
      ender_ = candidate_;
      ender_reliable_ = true;
    } else {
      candidate_ = last_key_;
    }
  }
  // Remember the date for epochs that bring none.
  if (cur_.has_tod) {
    if (cur_.has_date) {
      have_date_ = true;
      last_days_ = cur_.days;
      last_tod_ms_ = cur_.tod_ms;
    } else if (have_date_ && cur_.hasFix()) {
      // Only epochs with a fix move the clock on: receivers without a fix send
      // junk times (gp-320fw: 23:59:48 between 00:03 and 00:04), which would
      // otherwise fake a midnight.
      if (cur_.tod_ms + 12 * 3600 * 1000 < last_tod_ms_) ++last_days_;
      last_tod_ms_ = cur_.tod_ms;
    }
  }
  if (cur_.gsa_mode > 0 && cur_.has_tod) {
    last_gsa_mode_ = cur_.gsa_mode;
    last_gsa_tod_ms_ = cur_.tod_ms;
  }
  if (cur_.any_position_sentence) {
    Fix f = build(cur_);
    if (!emitted_) {
      emit(h, f);
    } else if (!sameFix(f, emitted_fix_)) {
      f.flags |= kFixUpdate;
      emit(h, f);
    }
  }
  cur_.open = false;
  emitted_ = false;
}

void FixAssembler::add(const Sentence& s, const NmeaRecord* rec, Handler& h) {
  // Epoch boundaries come from timed sentences (GST refers to a GGA and ZDA's
  // time is its own, so they do not open epochs; they still carry one).
  const bool opens = rec && rec->has_tod && rec->type != SentenceType::GST;
  if (opens && cur_.open && cur_.has_tod && cur_.tod_ms != rec->tod_ms) closeEpoch(h, true);
  // Without a time (a receiver still searching sends empty RMC/GGA/GLL
  // cycle after cycle) the repetition of a once-per-cycle sentence marks the
  // next cycle; otherwise those cycles would pile up into one epoch and taint
  // the first real fix (bt451: GLL,...,152504.50,A right after such cycles).
  if (rec && cur_.open && !cur_.has_tod && onePerCycle(rec->type) && seenInEpoch(s.address)) closeEpoch(h, false);
  // Data decoded after the learned ender that belongs to the same epoch (same
  // time, or no time) means the cycle goes on after it: keep merging;
  // closeEpoch() emits the completed fix as an update and moves the ender to
  // the epoch's last decoded sentence.
  if (!cur_.open) startEpoch();
  if (rec) apply(*rec);
  // Track the cycle: address and how often it occurred in this epoch.
  Key k;
  copyAddress(k.address, s.address);
  k.count = countOf(s.address);
  // Only decoded sentences can end a cycle: what follows the last of them (an
  // occasional GSV burst, a proprietary sentence) changes nothing in the fix.
  if (rec) last_key_ = k;
  if (opt_.early_emit && ender_reliable_ && !emitted_ && k == ender_ && cur_.has_tod) {
    if (cur_.any_position_sentence) {
      emitted_fix_ = build(cur_);
      emit(h, emitted_fix_);
    } else {
      emitted_fix_ = Fix::empty();
    }
    emitted_ = true;
  }
}

void FixAssembler::flush(Handler& h) { closeEpoch(h, false); }

// ===========================================================================
// NmeaDecoder

struct NmeaDecoder::Bridge final : SentenceReader::Handler, FixAssembler::Handler {
  NmeaDecoder& d;
  NmeaDecoder::Handler& h;
  Bridge(NmeaDecoder& dec, NmeaDecoder::Handler& handler) : d(dec), h(handler) {}
  void onSentence(const Sentence& s) override {
    NmeaDiagnostic diag;
    const bool ok = decodeSentence(s, &d.rec_, &diag);
    if (!ok && diag.code != NmeaError::None) {
      ++d.rejected_;
      h.onDiagnostic(diag);
      h.onSentence(s, nullptr);
      // A rejected sentence still marks the cycle, but carries nothing.
      d.assembler_.add(s, nullptr, *this);
      return;
    }
    h.onSentence(s, ok ? &d.rec_ : nullptr);
    d.assembler_.add(s, ok ? &d.rec_ : nullptr, *this);
  }
  void onDiagnostic(const NmeaDiagnostic& diag) override { h.onDiagnostic(diag); }
  void onFix(const Fix& f) override {
    ++d.fixes_;
    h.onFix(f);
  }
};

NmeaDecoder::NmeaDecoder(const Options& opt) : reader_(opt.reader), assembler_(opt.assembler) {}

void NmeaDecoder::feed(const void* data, size_t size, Handler& h) {
  Bridge b(*this, h);
  reader_.feed(data, size, b);
}

void NmeaDecoder::finish(Handler& h) {
  Bridge b(*this, h);
  reader_.finish(b);
  assembler_.flush(b);
}

void NmeaDecoder::reset() {
  reader_.reset();
  assembler_.reset();
  fixes_ = rejected_ = 0;
}

}  // namespace blvd::gnss
