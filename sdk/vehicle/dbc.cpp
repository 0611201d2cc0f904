#include "vehicle/dbc.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

namespace blvd::vehicle {
namespace {

constexpr uint32_t kExtendedBit = 0x80000000u;  // DBC: bit 31 of a BO_ id marks a 29-bit id
constexpr unsigned kMaxBits = kMaxFdLen * 8;

uint32_t key(uint32_t id, bool extended) { return id | (extended ? kExtendedBit : 0u); }

bool isIdentChar(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
}

// A cursor over one statement's text. Every getter skips leading blanks and
// returns false (leaving the cursor somewhere inside) when the token is not there.
struct Cursor {
  std::string_view s;
  size_t p = 0;

  void blanks() {
    while (p < s.size() && (s[p] == ' ' || s[p] == '\t' || s[p] == '\r' || s[p] == '\n')) ++p;
  }
  bool atEnd() {
    blanks();
    return p >= s.size();
  }
  bool peek(char c) {
    blanks();
    return p < s.size() && s[p] == c;
  }
  bool expect(char c) {
    if (!peek(c)) return false;
    ++p;
    return true;
  }
  bool ident(std::string_view& out) {
    blanks();
    const size_t b = p;
    while (p < s.size() && isIdentChar(s[p])) ++p;
    out = s.substr(b, p - b);
    return p > b;
  }
  bool unsignedInt(uint64_t& out, uint64_t max) {
    blanks();
    const char* b = s.data() + p;
    const auto r = std::from_chars(b, s.data() + s.size(), out);
    if (r.ec != std::errc() || out > max) return false;
    p += static_cast<size_t>(r.ptr - b);
    return true;
  }
  bool signedInt(int64_t& out) {
    blanks();
    size_t q = p;
    if (q < s.size() && s[q] == '+') ++q;  // from_chars takes '-' but not '+'
    const char* b = s.data() + q;
    const auto r = std::from_chars(b, s.data() + s.size(), out);
    if (r.ec != std::errc()) return false;
    p = q + static_cast<size_t>(r.ptr - b);
    return true;
  }
  // Locale-independent (strtod would read "0,01" in a German locale).
  bool number(double& out) {
    blanks();
    size_t q = p;
    if (q < s.size() && s[q] == '+') ++q;
    const char* b = s.data() + q;
    const auto r = std::from_chars(b, s.data() + s.size(), out, std::chars_format::general);
    if (r.ec != std::errc() || !std::isfinite(out)) return false;
    p = q + static_cast<size_t>(r.ptr - b);
    return true;
  }
  // "text" with \" and \\ escapes.
  bool quoted(std::string& out) {
    if (!expect('"')) return false;
    out.clear();
    while (p < s.size()) {
      const char c = s[p++];
      if (c == '"') return true;
      if (c == '\\' && p < s.size()) {
        out.push_back(s[p++]);
        continue;
      }
      out.push_back(c);
    }
    return false;
  }
};

// Number of '"' that open or close a string in `line` (escaped ones do not count),
// given whether the line starts inside a string. Returns whether it ends inside one.
bool endsInsideString(std::string_view line, bool inside) {
  for (size_t i = 0; i < line.size(); ++i) {
    if (inside && line[i] == '\\') {
      ++i;
      continue;
    }
    if (line[i] == '"') inside = !inside;
  }
  return inside;
}

// Walks the bit positions of a signal from its most significant bit to its least
// significant. Returns false when a position falls outside 64 bytes.
template <typename F>
bool forEachBitMsbFirst(const Signal& s, F&& f) {
  if (s.order == ByteOrder::Intel) {
    if (static_cast<unsigned>(s.start_bit) + s.length > kMaxBits) return false;
    for (int i = s.length - 1; i >= 0; --i) f(static_cast<unsigned>(s.start_bit + i));
    return true;
  }
  unsigned pos = s.start_bit;
  for (unsigned i = 0; i < s.length; ++i) {
    if (pos >= kMaxBits) return false;
    f(pos);
    pos = (pos % 8 == 0) ? pos + 15 : pos - 1;  // from bit 0 of a byte on to bit 7 of the next
  }
  return true;
}

std::string at(const std::string& source, uint32_t line) { return source + ":" + std::to_string(line) + ": "; }

struct PendingVal {
  uint32_t line;
  uint32_t key;
  std::string signal;
  std::vector<std::pair<int64_t, std::string>> values;
};
struct PendingType {
  uint32_t line;
  uint32_t key;
  std::string signal;
  int type;
};

}  // namespace

const std::string* Signal::describe(int64_t raw) const {
  for (const auto& v : values)
    if (v.first == raw) return &v.second;
  return nullptr;
}

const Signal* Message::signal(std::string_view signal_name) const {
  for (const auto& s : signals)
    if (s.name == signal_name) return &s;
  return nullptr;
}

const Message* Database::find(uint32_t id, bool extended) const {
  const auto it = by_id_.find(key(id, extended));
  return it == by_id_.end() ? nullptr : &messages_[it->second];
}

const Message* Database::findByName(std::string_view name) const {
  for (const auto& m : messages_)
    if (m.name == name) return &m;
  return nullptr;
}

blvd_status Database::load(const std::string& path, std::string& err, const DbcOptions& opt) {
  messages_.clear();
  by_id_.clear();
  diagnostics_.clear();
  std::ifstream f(path, std::ios::binary);
  if (!f) {
    err = path + ": cannot open: " + std::strerror(errno);
    return BLVD_ERR_IO;
  }
  std::ostringstream ss;
  ss << f.rdbuf();
  if (f.bad()) {
    err = path + ": read error";
    return BLVD_ERR_IO;
  }
  return parse(ss.str(), path, err, opt);
}

blvd_status Database::parse(std::string_view text, const std::string& source, std::string& err,
                            const DbcOptions& opt) {
  messages_.clear();
  by_id_.clear();
  diagnostics_.clear();
  source_ = source;
  std::vector<PendingVal> vals;
  std::vector<PendingType> types;
  std::vector<std::string> notes;

  const auto failWith = [&](blvd_status st, uint32_t line, const std::string& reason) {
    err = at(source, line) + reason;
    messages_.clear();
    by_id_.clear();
    diagnostics_.clear();
    return st;
  };

  if (text.size() >= 3 && text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);  // UTF-8 BOM
  size_t pos = 0;
  uint32_t line_no = 0;
  bool in_ns = false;            // inside the indented keyword list after "NS_ :"
  bool skipping_string = false;  // a skipped statement's quoted string runs on
  Message* current = nullptr;    // the BO_ whose SG_ lines follow
  bool skip_signals = false;     // signals of a pseudo message we do not keep

  while (pos < text.size()) {
    size_t eol = text.find('\n', pos);
    if (eol == std::string_view::npos) eol = text.size();
    std::string_view line = text.substr(pos, eol - pos);
    pos = eol + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);

    if (skipping_string) {
      skipping_string = endsInsideString(line, true);
      continue;
    }
    Cursor c{line};
    if (c.atEnd()) continue;
    const bool indented = line[0] == ' ' || line[0] == '\t';
    if (in_ns) {
      if (indented) continue;
      in_ns = false;
    }
    if (line.substr(c.p, 2) == "//") continue;
    std::string_view kw;
    if (!c.ident(kw)) {
      // Not a statement (stray text or the tail of a skipped one): skip it like any unknown statement.
      skipping_string = endsInsideString(line, false);
      continue;
    }

    if (kw == "SG_") {
      if (!current && !skip_signals) return failWith(BLVD_ERR_CORRUPT, line_no, "SG_ outside a BO_ message");
      if (skip_signals) continue;
      Signal s;
      s.line = line_no;
      std::string_view name;
      if (!c.ident(name)) return failWith(BLVD_ERR_CORRUPT, line_no, "SG_ without a signal name");
      s.name.assign(name);
      std::string_view mux;
      if (!c.peek(':')) {
        if (!c.ident(mux)) return failWith(BLVD_ERR_CORRUPT, line_no, "expected ':' after signal " + s.name);
        if (mux == "M") {
          s.multiplexor = true;
        } else if (mux.size() >= 2 && mux[0] == 'm') {
          std::string_view digits = mux.substr(1);
          if (digits.back() == 'M') {  // extended multiplexing: multiplexed and a multiplexor itself
            s.multiplexor = true;
            digits.remove_suffix(1);
          }
          int64_t v = -1;
          const auto r = std::from_chars(digits.data(), digits.data() + digits.size(), v);
          if (r.ec != std::errc() || r.ptr != digits.data() + digits.size() || v < 0 || v > INT32_MAX)
            return failWith(BLVD_ERR_CORRUPT, line_no,
                            "bad multiplexer indicator '" + std::string(mux) + "' for signal " + s.name);
          s.multiplex_value = static_cast<int32_t>(v);
        } else {
          return failWith(BLVD_ERR_CORRUPT, line_no,
                          "bad multiplexer indicator '" + std::string(mux) + "' for signal " + s.name);
        }
      }
      uint64_t start = 0, len = 0;
      if (!c.expect(':') || !c.unsignedInt(start, 65535) || !c.expect('|') || !c.unsignedInt(len, 65535) ||
          !c.expect('@'))
        return failWith(BLVD_ERR_CORRUPT, line_no, "signal " + s.name + ": expected ': START|LENGTH@'");
      if (c.p >= line.size() || (line[c.p] != '0' && line[c.p] != '1'))
        return failWith(BLVD_ERR_CORRUPT, line_no, "signal " + s.name + ": byte order must be @0 or @1");
      s.order = line[c.p++] == '1' ? ByteOrder::Intel : ByteOrder::Motorola;
      if (c.p >= line.size() || (line[c.p] != '+' && line[c.p] != '-'))
        return failWith(BLVD_ERR_CORRUPT, line_no, "signal " + s.name + ": expected + or - after the byte order");
      s.is_signed = line[c.p++] == '-';
      if (len < 1 || len > 64)
        return failWith(BLVD_ERR_CORRUPT, line_no,
                        "signal " + s.name + ": length " + std::to_string(len) + " is not 1..64 bits");
      s.start_bit = static_cast<uint16_t>(start);
      s.length = static_cast<uint16_t>(len);
      if (!c.expect('(') || !c.number(s.factor) || !c.expect(',') || !c.number(s.offset) || !c.expect(')'))
        return failWith(BLVD_ERR_CORRUPT, line_no, "signal " + s.name + ": expected (FACTOR,OFFSET)");
      if (s.factor == 0) return failWith(BLVD_ERR_CORRUPT, line_no, "signal " + s.name + ": factor is 0");
      if (!c.expect('[') || !c.number(s.minimum) || !c.expect('|') || !c.number(s.maximum) || !c.expect(']'))
        return failWith(BLVD_ERR_CORRUPT, line_no, "signal " + s.name + ": expected [MIN|MAX]");
      if (!c.quoted(s.unit)) return failWith(BLVD_ERR_CORRUPT, line_no, "signal " + s.name + ": expected \"UNIT\"");
      while (!c.atEnd()) {
        if (c.expect(',')) continue;
        std::string_view r;
        if (!c.ident(r))
          return failWith(BLVD_ERR_CORRUPT, line_no,
                          "signal " + s.name + ": bad receiver list near '" + std::string(line.substr(c.p, 20)) + "'");
        s.receivers.emplace_back(r);
      }
      unsigned last_byte = 0;
      if (!forEachBitMsbFirst(s, [&](unsigned b) { last_byte = std::max(last_byte, b / 8); }))
        return failWith(BLVD_ERR_CORRUPT, line_no,
                        "signal " + s.name + ": bits " + std::to_string(start) + "|" + std::to_string(len) +
                            " run outside a 64-byte frame");
      s.bytes_needed = static_cast<uint16_t>(last_byte + 1);
      if (s.bytes_needed > current->size)
        notes.push_back(at(source, line_no) + "signal " + s.name + " reaches byte " + std::to_string(last_byte) +
                        " of message " + current->name + ", which has " + std::to_string(current->size) + " bytes");
      if (s.multiplex_value >= 0) {
        s.supported = false;
        s.unsupported = "unsupported: multiplexed signal " + s.name + " in message " + current->name + " (line " +
                        std::to_string(line_no) + ")";
        if (opt.reject_unsupported) return failWith(BLVD_ERR_UNSUPPORTED, line_no, s.unsupported);
        diagnostics_.push_back(at(source, line_no) + s.unsupported);
      }
      for (const auto& other : current->signals)
        if (other.name == s.name)
          return failWith(BLVD_ERR_CORRUPT, line_no,
                          "signal " + s.name + " declared twice in message " + current->name + " (first at line " +
                              std::to_string(other.line) + ")");
      current->signals.push_back(std::move(s));
      continue;
    }

    current = nullptr;
    skip_signals = false;

    if (kw == "BO_") {
      if (c.atEnd()) continue;  // a bare keyword (keyword list)
      uint64_t raw_id = 0, size = 0;
      std::string_view name;
      if (!c.unsignedInt(raw_id, 0xFFFFFFFFu)) return failWith(BLVD_ERR_CORRUPT, line_no, "BO_ without a numeric id");
      if (!c.ident(name)) return failWith(BLVD_ERR_CORRUPT, line_no, "BO_ without a message name");
      if (!c.expect(':') || !c.unsignedInt(size, 0xFFFF))
        return failWith(BLVD_ERR_CORRUPT, line_no, "message " + std::string(name) + ": expected ': SIZE'");
      std::string_view tx;
      c.ident(tx);  // optional
      if (!c.atEnd())
        return failWith(BLVD_ERR_CORRUPT, line_no,
                        "message " + std::string(name) + ": unexpected text '" + std::string(line.substr(c.p)) + "'");
      if (name == "VECTOR__INDEPENDENT_SIG_MSG") {  // a container for unplaced signals, not a frame
        skip_signals = true;
        continue;
      }
      if (size > kMaxFdLen)
        return failWith(BLVD_ERR_CORRUPT, line_no,
                        "message " + std::string(name) + ": size " + std::to_string(size) + " exceeds 64 bytes");
      Message m;
      m.extended = (raw_id & kExtendedBit) != 0;
      m.id = static_cast<uint32_t>(raw_id & ~kExtendedBit);
      if (m.extended ? m.id > kEffMask : m.id > kSffMask)
        return failWith(BLVD_ERR_CORRUPT, line_no,
                        "message " + std::string(name) + ": id " + std::to_string(raw_id) +
                            (m.extended ? " exceeds 29 bits" : " exceeds 0x7FF (extended ids set bit 31)"));
      m.name.assign(name);
      m.size = static_cast<uint32_t>(size);
      m.transmitter.assign(tx);
      m.line = line_no;
      const auto k = key(m.id, m.extended);
      if (const auto it = by_id_.find(k); it != by_id_.end())
        return failWith(BLVD_ERR_CORRUPT, line_no,
                        "message " + m.name + ": id " + std::to_string(raw_id) + " already used by " +
                            messages_[it->second].name + " (line " + std::to_string(messages_[it->second].line) + ")");
      by_id_.emplace(k, messages_.size());
      messages_.push_back(std::move(m));
      current = &messages_.back();
      continue;
    }

    if (kw == "NS_") {
      in_ns = true;
      continue;
    }

    if (kw == "VAL_") {
      // VAL_ id signal int "text" ... ; on one line. Anything else is ignored: descriptions are optional.
      PendingVal v;
      v.line = line_no;
      uint64_t raw_id = 0;
      std::string_view sig;
      bool ok = c.unsignedInt(raw_id, 0xFFFFFFFFu) && c.ident(sig);
      while (ok && !c.expect(';')) {
        int64_t n = 0;
        std::string d;
        ok = c.signedInt(n) && c.quoted(d);
        if (ok) v.values.emplace_back(n, std::move(d));
      }
      if (ok) {
        v.key = key(static_cast<uint32_t>(raw_id & ~kExtendedBit), (raw_id & kExtendedBit) != 0);
        v.signal.assign(sig);
        vals.push_back(std::move(v));
      } else {
        skipping_string = endsInsideString(line, false);
      }
      continue;
    }

    if (kw == "SIG_VALTYPE_") {
      uint64_t raw_id = 0, type = 0;
      std::string_view sig;
      if (c.unsignedInt(raw_id, 0xFFFFFFFFu) && c.ident(sig) && c.expect(':') && c.unsignedInt(type, 3)) {
        types.push_back({line_no, key(static_cast<uint32_t>(raw_id & ~kExtendedBit), (raw_id & kExtendedBit) != 0),
                         std::string(sig), static_cast<int>(type)});
      } else {
        notes.push_back(at(source, line_no) + "SIG_VALTYPE_ not understood; ignored");
      }
      continue;
    }

    // CM_ and everything else: skipped, including a quoted string running on over lines.
    skipping_string = endsInsideString(line, false);
  }

  const auto findSignal = [&](uint32_t k, const std::string& name) -> Signal* {
    const auto it = by_id_.find(k);
    if (it == by_id_.end()) return nullptr;
    for (auto& s : messages_[it->second].signals)
      if (s.name == name) return &s;
    return nullptr;
  };
  for (auto& v : vals)
    if (Signal* s = findSignal(v.key, v.signal)) s->values = std::move(v.values);
  for (const auto& t : types) {
    Signal* s = findSignal(t.key, t.signal);
    if (!s) {
      notes.push_back(at(source, t.line) + "SIG_VALTYPE_ for unknown signal " + t.signal);
      continue;
    }
    if (t.type == 1 || t.type == 2) {
      const unsigned want = t.type == 1 ? 32 : 64;
      if (s->length != want) {
        s->supported = false;
        s->unsupported = "unsupported: signal " + s->name + " is declared IEEE float but has " +
                         std::to_string(s->length) + " bits (line " + std::to_string(t.line) + ")";
        if (opt.reject_unsupported) return failWith(BLVD_ERR_UNSUPPORTED, t.line, s->unsupported);
        diagnostics_.push_back(at(source, t.line) + s->unsupported);
        continue;
      }
      s->type = t.type == 1 ? ValueType::Float32 : ValueType::Float64;
    }
  }
  for (auto& n : notes) diagnostics_.push_back(std::move(n));
  return BLVD_OK;
}

// ---- bits ----------------------------------------------------------------------

uint64_t extractRaw(const Signal& s, const uint8_t* data) {
  uint64_t v = 0;
  forEachBitMsbFirst(s, [&](unsigned b) { v = (v << 1) | ((data[b / 8] >> (b % 8)) & 1u); });
  return v;
}

void insertRaw(const Signal& s, uint64_t raw, uint8_t* data) {
  int i = s.length - 1;
  forEachBitMsbFirst(s, [&](unsigned b) {
    const uint8_t mask = static_cast<uint8_t>(1u << (b % 8));
    if ((raw >> i) & 1u)
      data[b / 8] |= mask;
    else
      data[b / 8] &= static_cast<uint8_t>(~mask);
    --i;
  });
}

double toPhysical(const Signal& s, uint64_t raw) {
  double v;
  if (s.type == ValueType::Float32) {
    const uint32_t bits = static_cast<uint32_t>(raw);
    float f;
    std::memcpy(&f, &bits, sizeof f);
    v = f;
  } else if (s.type == ValueType::Float64) {
    std::memcpy(&v, &raw, sizeof v);
  } else if (s.is_signed && s.length < 64 && ((raw >> (s.length - 1)) & 1u)) {
    v = static_cast<double>(static_cast<int64_t>(raw | (~uint64_t{0} << s.length)));
  } else if (s.is_signed) {
    v = static_cast<double>(static_cast<int64_t>(raw));
  } else {
    v = static_cast<double>(raw);
  }
  return v * s.factor + s.offset;
}

bool toRaw(const Signal& s, double value, uint64_t& raw) {
  if (!std::isfinite(value)) return false;
  const double x = (value - s.offset) / s.factor;
  if (s.type == ValueType::Float32) {
    const float f = static_cast<float>(x);
    if (!std::isfinite(f)) return false;
    uint32_t bits;
    std::memcpy(&bits, &f, sizeof bits);
    raw = bits;
    return true;
  }
  if (s.type == ValueType::Float64) {
    std::memcpy(&raw, &x, sizeof raw);
    return true;
  }
  const double r = std::nearbyint(x);
  if (s.is_signed) {
    const double lo = -std::ldexp(1.0, s.length - 1), hi = std::ldexp(1.0, s.length - 1);
    if (!(r >= lo && r < hi)) return false;
    const int64_t n = static_cast<int64_t>(r);
    raw = static_cast<uint64_t>(n) & (s.length == 64 ? ~uint64_t{0} : ((uint64_t{1} << s.length) - 1));
  } else {
    if (!(r >= 0 && r < std::ldexp(1.0, s.length))) return false;
    raw = static_cast<uint64_t>(r);
  }
  return true;
}

size_t decode(const Message& m, const Frame& f, std::vector<DecodedSignal>& out) {
  out.clear();
  if (f.rtr || f.error) return 0;
  for (const auto& s : m.signals) {
    if (!s.supported || s.bytes_needed > f.dlc) continue;
    DecodedSignal d;
    d.signal = &s;
    d.raw = extractRaw(s, f.data);
    d.value = toPhysical(s, d.raw);
    out.push_back(d);
  }
  return out.size();
}

namespace {

blvd_status prepare(const Message& m, Frame& f) {
  f.id = m.id;
  f.extended = m.extended;
  f.rtr = f.error = false;
  if (f.dlc < m.size) {
    f.dlc = static_cast<uint8_t>(m.size);
    if (m.size > kMaxClassicLen) f.fd = true;
  }
  return BLVD_OK;
}

blvd_status encodeOne(const Signal& s, double value, const uint64_t* decoded_raw, Frame& f, std::string& err) {
  if (!s.supported) {
    err = s.unsupported;
    return BLVD_ERR_UNSUPPORTED;
  }
  uint64_t raw = 0;
  // A value straight from decode() is written back as its raw bits, which is exact
  // even where a double cannot hold every value of a wide signal.
  double back = 0;
  if (decoded_raw) back = toPhysical(s, *decoded_raw);
  if (decoded_raw && std::memcmp(&back, &value, sizeof back) == 0) {
    raw = *decoded_raw;
  } else if (!toRaw(s, value, raw)) {
    err = "signal " + s.name + ": value " + std::to_string(value) + " does not fit " + std::to_string(s.length) +
          (s.is_signed ? " signed" : " unsigned") + " bits";
    return BLVD_ERR_INVALID_ARG;
  }
  if (s.bytes_needed > f.dlc) f.dlc = static_cast<uint8_t>(s.bytes_needed);
  insertRaw(s, raw, f.data);
  return BLVD_OK;
}

}  // namespace

blvd_status encode(const Message& m, const std::vector<DecodedSignal>& values, Frame& f, std::string& err) {
  prepare(m, f);
  for (const auto& v : values) {
    if (!v.signal || v.signal < m.signals.data() || v.signal >= m.signals.data() + m.signals.size()) {
      err = "encode: a signal does not belong to message " + m.name;
      return BLVD_ERR_MISUSE;
    }
    if (const blvd_status st = encodeOne(*v.signal, v.value, &v.raw, f, err); st != BLVD_OK) return st;
  }
  return BLVD_OK;
}

blvd_status encode(const Message& m, const std::vector<std::pair<std::string, double>>& values, Frame& f,
                   std::string& err) {
  prepare(m, f);
  for (const auto& [name, value] : values) {
    const Signal* s = m.signal(name);
    if (!s) {
      err = "message " + m.name + " has no signal " + name;
      return BLVD_ERR_NOT_FOUND;
    }
    if (const blvd_status st = encodeOne(*s, value, nullptr, f, err); st != BLVD_OK) return st;
  }
  return BLVD_OK;
}

}  // namespace blvd::vehicle
