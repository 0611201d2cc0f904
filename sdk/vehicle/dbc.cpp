#include "vehicle/dbc.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <cstdio>
#include <memory>

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

// The whole file. Not through iostreams: they turn a failed allocation into a
// short read, and part of a file would load as if it were all of it.
core::Status readAll(const std::string& path, std::string& text, std::string& err) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) return err = path + ": cannot open: " + std::strerror(errno), core::Status::Io;
  char buf[16384];
  for (size_t n; (n = std::fread(buf, 1, sizeof buf, f.get())) > 0;) text.append(buf, n);
  if (std::ferror(f.get())) return err = path + ": read error", core::Status::Io;
  return core::Status::Ok;
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
struct PendingMulVal {  // SG_MUL_VAL_: extended multiplexing of a message
  uint32_t line;
  uint32_t key;
};

// Simple multiplexing only: at most one 'M' signal, every 'mN' signal under it.
// Sets m.multiplexor; otherwise says why the message cannot be decoded.
std::string multiplexProblem(Message& m, core::Status& st) {
  int32_t mux = -1;
  st = core::Status::Unsupported;
  for (size_t i = 0; i < m.signals.size(); ++i) {
    const Signal& s = m.signals[i];
    if (!s.multiplexor) continue;
    if (s.multiplex_value >= 0) return "extended multiplexing: signal " + s.name + " is multiplexed and a multiplexor";
    if (mux >= 0) return "more than one multiplexor (" + m.signals[size_t(mux)].name + ", " + s.name + ")";
    mux = static_cast<int32_t>(i);
  }
  for (const Signal& s : m.signals)
    if (s.multiplex_value >= 0 && mux < 0)
      return st = core::Status::Corrupt, "multiplexed signal " + s.name + " without a multiplexor";
  if (mux >= 0 && (!m.signals[size_t(mux)].supported || m.signals[size_t(mux)].type != ValueType::Integer))
    return "multiplexor " + m.signals[size_t(mux)].name + " is not an integer signal";
  m.multiplexor = mux;
  return {};
}

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

core::Status Database::load(const std::string& path, std::string& err, const DbcOptions& opt) {
  messages_.clear();
  by_id_.clear();
  diagnostics_.clear();
  skipped_.clear();
  std::string text;
  if (const core::Status st = readAll(path, text, err); st != core::Status::Ok) return st;
  return parse(text, path, err, opt);
}

// One DBC text being read, a line at a time: the statements' state between
// lines, and what is resolved after the last (VAL_, SIG_VALTYPE_ and
// SG_MUL_VAL_ refer to messages by id and may come before them). Messages to
// skip are marked and left out at the end.
class Database::Parser {
 public:
  Parser(Database& db, const std::string& source, const DbcOptions& opt) : db_(db), source_(source), opt_(opt) {}
  // False on a fatal error: status(), line() and reason() say which.
  bool line(std::string_view line, uint32_t line_no);
  bool finish();
  core::Status status() const { return status_; }
  uint32_t errorLine() const { return error_line_; }
  const std::string& reason() const { return reason_; }

 private:
  bool fail(core::Status st, uint32_t line_no, std::string reason) {
    status_ = st, error_line_ = line_no, reason_ = std::move(reason);
    return false;
  }
  void note(uint32_t line_no, std::string text) { notes_.emplace_back(line_no, at(source_, line_no) + text); }
  bool skip(core::Status st, uint32_t line_no, const std::string& name, const std::string& reason);
  bool dropCurrent(core::Status st, uint32_t line_no, const std::string& reason);
  bool drop(size_t index, core::Status st, uint32_t line_no, const std::string& reason);
  bool signal(Cursor& c, std::string_view line, uint32_t line_no);
  bool multiplexer(Cursor& c, Signal& s, std::string& why);
  bool layout(Cursor& c, std::string_view line, Signal& s, std::string& why);
  bool placed(Signal& s, uint32_t line_no, std::string& why);
  bool message(Cursor& c, std::string_view line, uint32_t line_no);
  void valueTable(Cursor& c, std::string_view line, uint32_t line_no);
  void valueType(Cursor& c, uint32_t line_no);
  void mulVal(Cursor& c, uint32_t line_no);
  bool resolveTypes();
  bool checkMessages();
  void keepUsable();
  Signal* findSignal(uint32_t k, const std::string& name);

  Database& db_;
  const std::string& source_;
  const DbcOptions& opt_;
  bool in_ns_ = false;            // inside the indented keyword list after "NS_ :"
  bool skipping_string_ = false;  // a skipped statement's quoted string runs on
  Message* current_ = nullptr;    // the BO_ whose SG_ lines follow
  bool skip_signals_ = false;     // signals of a message we do not keep
  std::vector<uint8_t> dropped_;  // per message of db_.messages_: skipped
  std::vector<PendingVal> vals_;
  std::vector<PendingType> types_;
  std::vector<PendingMulVal> mul_vals_;
  std::vector<std::pair<uint32_t, std::string>> notes_;  // line, text
  core::Status status_ = core::Status::Ok;
  uint32_t error_line_ = 0;
  std::string reason_;
};

// A message the decoder cannot use: the load fails when strict, else it is noted and left out.
bool Database::Parser::skip(core::Status st, uint32_t line_no, const std::string& name, const std::string& reason) {
  if (opt_.strict) return fail(st, line_no, name.empty() ? reason : "message " + name + ": " + reason);
  note(line_no, (name.empty() ? std::string("skipped: ") : "message " + name + " skipped: ") + reason);
  db_.skipped_.push_back({name, line_no, reason});
  return true;
}

bool Database::Parser::drop(size_t index, core::Status st, uint32_t line_no, const std::string& reason) {
  if (dropped_[index]) return true;
  dropped_[index] = 1;
  return skip(st, line_no, db_.messages_[index].name, reason);
}

// The message being read is skipped, and its SG_ lines after this one with it.
bool Database::Parser::dropCurrent(core::Status st, uint32_t line_no, const std::string& reason) {
  const size_t index = static_cast<size_t>(current_ - db_.messages_.data());
  current_ = nullptr;
  skip_signals_ = true;
  return drop(index, st, line_no, reason);
}

bool Database::Parser::line(std::string_view line, uint32_t line_no) {
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  if (skipping_string_) {
    skipping_string_ = endsInsideString(line, true);
    return true;
  }
  Cursor c{line};
  if (c.atEnd()) return true;
  const bool indented = line[0] == ' ' || line[0] == '\t';
  if (in_ns_) {
    if (indented) return true;
    in_ns_ = false;
  }
  if (line.substr(c.p, 2) == "//") return true;
  std::string_view kw;
  if (!c.ident(kw)) {
    // Not a statement (stray text or the tail of a skipped one): skip it like any unknown statement.
    skipping_string_ = endsInsideString(line, false);
    return true;
  }
  if (kw == "SG_") return signal(c, line, line_no);
  current_ = nullptr;
  skip_signals_ = false;
  if (kw == "BO_") return message(c, line, line_no);
  if (kw == "NS_") {
    in_ns_ = true;
  } else if (kw == "VAL_") {
    valueTable(c, line, line_no);
  } else if (kw == "SIG_VALTYPE_") {
    valueType(c, line_no);
  } else if (kw == "SG_MUL_VAL_") {
    mulVal(c, line_no);
  } else {
    // CM_ and everything else: skipped, including a quoted string running on over lines.
    skipping_string_ = endsInsideString(line, false);
  }
  return true;
}

// SG_ NAME [M|mN|mNM] : START|LENGTH@ORDER SIGN (FACTOR,OFFSET) [MIN|MAX] "UNIT" RECEIVERS
bool Database::Parser::signal(Cursor& c, std::string_view line, uint32_t line_no) {
  if (skip_signals_) return true;
  if (!current_) {
    if (opt_.strict) return fail(core::Status::Corrupt, line_no, "SG_ outside a BO_ message");
    note(line_no, "SG_ outside a BO_ message; ignored");
    return true;
  }
  Signal s;
  s.line = line_no;
  std::string_view name;
  std::string why;
  if (!c.ident(name)) return dropCurrent(core::Status::Corrupt, line_no, "SG_ without a signal name");
  s.name.assign(name);
  if (!multiplexer(c, s, why) || !layout(c, line, s, why) || !placed(s, line_no, why))
    return dropCurrent(core::Status::Corrupt, line_no, why);
  for (const auto& other : current_->signals)
    if (other.name == s.name)
      return dropCurrent(core::Status::Corrupt, line_no,
                         "signal " + s.name + " declared twice (first at line " + std::to_string(other.line) + ")");
  current_->signals.push_back(std::move(s));
  return true;
}

// The optional multiplexer indicator between the name and the ':'.
bool Database::Parser::multiplexer(Cursor& c, Signal& s, std::string& why) {
  if (c.peek(':')) return true;
  std::string_view mux;
  if (!c.ident(mux)) return why = "expected ':' after signal " + s.name, false;
  if (mux == "M") {
    s.multiplexor = true;
    return true;
  }
  const std::string bad = "bad multiplexer indicator '" + std::string(mux) + "' for signal " + s.name;
  if (mux.size() < 2 || mux[0] != 'm') return why = bad, false;
  std::string_view digits = mux.substr(1);
  if (digits.back() == 'M') {  // extended multiplexing: multiplexed and a multiplexor itself
    s.multiplexor = true;
    digits.remove_suffix(1);
  }
  int64_t v = -1;
  const auto r = std::from_chars(digits.data(), digits.data() + digits.size(), v);
  if (r.ec != std::errc() || r.ptr != digits.data() + digits.size() || v < 0 || v > INT32_MAX) return why = bad, false;
  s.multiplex_value = static_cast<int32_t>(v);
  return true;
}

// From the ':' to the end of the line.
bool Database::Parser::layout(Cursor& c, std::string_view line, Signal& s, std::string& why) {
  const std::string sig = "signal " + s.name + ": ";
  uint64_t start = 0, len = 0;
  if (!c.expect(':') || !c.unsignedInt(start, 65535) || !c.expect('|') || !c.unsignedInt(len, 65535) ||
      !c.expect('@'))
    return why = sig + "expected ': START|LENGTH@'", false;
  if (c.p >= line.size() || (line[c.p] != '0' && line[c.p] != '1')) return why = sig + "byte order must be @0 or @1", false;
  s.order = line[c.p++] == '1' ? ByteOrder::Intel : ByteOrder::Motorola;
  if (c.p >= line.size() || (line[c.p] != '+' && line[c.p] != '-'))
    return why = sig + "expected + or - after the byte order", false;
  s.is_signed = line[c.p++] == '-';
  if (len < 1 || len > 64) return why = sig + "length " + std::to_string(len) + " is not 1..64 bits", false;
  s.start_bit = static_cast<uint16_t>(start);
  s.length = static_cast<uint16_t>(len);
  if (!c.expect('(') || !c.number(s.factor) || !c.expect(',') || !c.number(s.offset) || !c.expect(')'))
    return why = sig + "expected (FACTOR,OFFSET)", false;
  if (s.factor == 0) return why = sig + "factor is 0", false;
  if (!c.expect('[') || !c.number(s.minimum) || !c.expect('|') || !c.number(s.maximum) || !c.expect(']'))
    return why = sig + "expected [MIN|MAX]", false;
  if (!c.quoted(s.unit)) return why = sig + "expected \"UNIT\"", false;
  while (!c.atEnd()) {
    if (c.expect(',')) continue;
    std::string_view r;
    if (!c.ident(r)) return why = sig + "bad receiver list near '" + std::string(line.substr(c.p, 20)) + "'", false;
    s.receivers.emplace_back(r);
  }
  return true;
}

// The signal's bits within a 64-byte frame and its message's size.
bool Database::Parser::placed(Signal& s, uint32_t line_no, std::string& why) {
  unsigned last_byte = 0;
  if (!forEachBitMsbFirst(s, [&](unsigned b) { last_byte = std::max(last_byte, b / 8); }))
    return why = "signal " + s.name + ": bits " + std::to_string(s.start_bit) + "|" + std::to_string(s.length) +
                 " run outside a 64-byte frame",
           false;
  s.bytes_needed = static_cast<uint16_t>(last_byte + 1);
  if (s.bytes_needed > current_->size)
    note(line_no, "signal " + s.name + " reaches byte " + std::to_string(last_byte) + " of message " + current_->name +
                      ", which has " + std::to_string(current_->size) + " bytes");
  return true;
}

// BO_ ID NAME: SIZE [TRANSMITTER]
bool Database::Parser::message(Cursor& c, std::string_view line, uint32_t line_no) {
  if (c.atEnd()) return true;  // a bare keyword (keyword list)
  uint64_t raw_id = 0, size = 0;
  std::string_view name;
  skip_signals_ = true;  // until the message is taken
  if (!c.unsignedInt(raw_id, 0xFFFFFFFFu)) return skip(core::Status::Corrupt, line_no, "", "BO_ without a numeric id");
  if (!c.ident(name)) return skip(core::Status::Corrupt, line_no, "", "BO_ without a message name");
  const std::string n(name);
  if (!c.expect(':') || !c.unsignedInt(size, 0xFFFF)) return skip(core::Status::Corrupt, line_no, n, "expected ': SIZE'");
  std::string_view tx;
  c.ident(tx);  // optional
  if (!c.atEnd())
    return skip(core::Status::Corrupt, line_no, n, "unexpected text '" + std::string(line.substr(c.p)) + "'");
  if (name == "VECTOR__INDEPENDENT_SIG_MSG") return true;  // a container for unplaced signals, not a frame
  if (size > kMaxFdLen) return skip(core::Status::Corrupt, line_no, n, "size " + std::to_string(size) + " exceeds 64 bytes");
  Message m;
  m.extended = (raw_id & kExtendedBit) != 0;
  m.id = static_cast<uint32_t>(raw_id & ~kExtendedBit);
  if (m.extended ? m.id > kEffMask : m.id > kSffMask)
    return skip(core::Status::Corrupt, line_no, n,
                "id " + std::to_string(raw_id) + (m.extended ? " exceeds 29 bits" : " exceeds 0x7FF (extended ids set bit 31)"));
  const auto k = key(m.id, m.extended);
  if (const auto it = db_.by_id_.find(k); it != db_.by_id_.end())
    return skip(core::Status::Corrupt, line_no, n,
                "id " + std::to_string(raw_id) + " already used by " + db_.messages_[it->second].name + " (line " +
                    std::to_string(db_.messages_[it->second].line) + ")");
  m.name = n;
  m.size = static_cast<uint32_t>(size);
  m.transmitter.assign(tx);
  m.line = line_no;
  db_.by_id_.emplace(k, db_.messages_.size());
  db_.messages_.push_back(std::move(m));
  dropped_.push_back(0);
  current_ = &db_.messages_.back();
  skip_signals_ = false;
  return true;
}

// VAL_ id signal int "text" ... ; on one line (the ; may be missing). Anything else is noted and ignored.
void Database::Parser::valueTable(Cursor& c, std::string_view line, uint32_t line_no) {
  PendingVal v;
  v.line = line_no;
  uint64_t raw_id = 0;
  std::string_view sig;
  bool ok = c.unsignedInt(raw_id, 0xFFFFFFFFu) && c.ident(sig);
  while (ok && !c.expect(';') && !c.atEnd()) {  // some files end a VAL_ line without its ';'
    int64_t n = 0;
    std::string d;
    ok = c.signedInt(n) && c.quoted(d);
    if (ok) v.values.emplace_back(n, std::move(d));
  }
  if (!ok) {
    note(line_no, "VAL_ not understood; ignored");
    skipping_string_ = endsInsideString(line, false);
    return;
  }
  v.key = key(static_cast<uint32_t>(raw_id & ~kExtendedBit), (raw_id & kExtendedBit) != 0);
  v.signal.assign(sig);
  vals_.push_back(std::move(v));
}

// SIG_VALTYPE_ id signal : type ;
void Database::Parser::valueType(Cursor& c, uint32_t line_no) {
  uint64_t raw_id = 0, type = 0;
  std::string_view sig;
  if (c.unsignedInt(raw_id, 0xFFFFFFFFu) && c.ident(sig) && c.expect(':') && c.unsignedInt(type, 3)) {
    types_.push_back({line_no, key(static_cast<uint32_t>(raw_id & ~kExtendedBit), (raw_id & kExtendedBit) != 0),
                      std::string(sig), static_cast<int>(type)});
  } else {
    note(line_no, "SIG_VALTYPE_ not understood; ignored");
  }
}

// SG_MUL_VAL_ id multiplexed_signal multiplexor_signal ranges ; (only the id is needed).
void Database::Parser::mulVal(Cursor& c, uint32_t line_no) {
  uint64_t raw_id = 0;
  if (c.unsignedInt(raw_id, 0xFFFFFFFFu))
    mul_vals_.push_back({line_no, key(static_cast<uint32_t>(raw_id & ~kExtendedBit), (raw_id & kExtendedBit) != 0)});
  else
    note(line_no, "SG_MUL_VAL_ not understood; ignored");
}

Signal* Database::Parser::findSignal(uint32_t k, const std::string& name) {
  const auto it = db_.by_id_.find(k);
  if (it == db_.by_id_.end()) return nullptr;
  for (auto& s : db_.messages_[it->second].signals)
    if (s.name == name) return &s;
  return nullptr;
}

// Float types onto their signals; a length that does not match leaves the signal out.
bool Database::Parser::resolveTypes() {
  for (const auto& t : types_) {
    Signal* s = findSignal(t.key, t.signal);
    if (!s) {
      note(t.line, "SIG_VALTYPE_ for unknown signal " + t.signal);
      continue;
    }
    if (t.type != 1 && t.type != 2) continue;
    const unsigned want = t.type == 1 ? 32 : 64;
    if (s->length == want) {
      s->type = t.type == 1 ? ValueType::Float32 : ValueType::Float64;
      continue;
    }
    s->supported = false;
    s->unsupported = "unsupported: signal " + s->name + " is declared IEEE float but has " +
                     std::to_string(s->length) + " bits (line " + std::to_string(t.line) + ")";
    if (opt_.strict) return fail(core::Status::Unsupported, t.line, s->unsupported);
    note(t.line, s->unsupported);
  }
  return true;
}

// Messages under extended multiplexing (SG_MUL_VAL_) or with a multiplexing
// this decoder does not follow are skipped.
bool Database::Parser::checkMessages() {
  for (const auto& mv : mul_vals_) {
    const auto it = db_.by_id_.find(mv.key);
    if (it != db_.by_id_.end() &&
        !drop(it->second, core::Status::Unsupported, db_.messages_[it->second].line,
              "extended multiplexing (SG_MUL_VAL_, line " + std::to_string(mv.line) + ")"))
      return false;
  }
  for (size_t i = 0; i < db_.messages_.size(); ++i) {
    core::Status st = core::Status::Ok;
    const std::string why = dropped_[i] ? std::string() : multiplexProblem(db_.messages_[i], st);
    if (!why.empty() && !drop(i, st, db_.messages_[i].line, why)) return false;
  }
  return true;
}

// The skipped messages out, the index rebuilt, the notes in file order.
void Database::Parser::keepUsable() {
  std::vector<Message> kept;
  kept.reserve(db_.messages_.size());
  for (size_t i = 0; i < db_.messages_.size(); ++i)
    if (!dropped_[i]) kept.push_back(std::move(db_.messages_[i]));
  db_.messages_ = std::move(kept);
  db_.by_id_.clear();
  for (size_t i = 0; i < db_.messages_.size(); ++i)
    db_.by_id_.emplace(key(db_.messages_[i].id, db_.messages_[i].extended), i);
  std::stable_sort(notes_.begin(), notes_.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (auto& n : notes_) db_.diagnostics_.push_back(std::move(n.second));
  std::stable_sort(db_.skipped_.begin(), db_.skipped_.end(),
                   [](const SkippedMessage& a, const SkippedMessage& b) { return a.line < b.line; });
}

bool Database::Parser::finish() {
  for (auto& v : vals_)
    if (Signal* s = findSignal(v.key, v.signal)) s->values = std::move(v.values);
  if (!resolveTypes() || !checkMessages()) return false;
  keepUsable();
  if (db_.messages_.empty() && !db_.skipped_.empty())
    return fail(core::Status::Corrupt, db_.skipped_.front().line,
                "no message could be used (" + std::to_string(db_.skipped_.size()) + " skipped; the first: " +
                    db_.skipped_.front().reason + ")");
  return true;
}

core::Status Database::parse(std::string_view text, const std::string& source, std::string& err,
                            const DbcOptions& opt) {
  messages_.clear();
  by_id_.clear();
  diagnostics_.clear();
  skipped_.clear();
  source_ = source;
  if (text.size() >= 3 && text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);  // UTF-8 BOM
  Parser p(*this, source, opt);
  bool ok = true;
  uint32_t line_no = 0;
  for (size_t pos = 0; ok && pos < text.size();) {
    size_t eol = text.find('\n', pos);
    if (eol == std::string_view::npos) eol = text.size();
    ok = p.line(text.substr(pos, eol - pos), ++line_no);
    pos = eol + 1;
  }
  if (ok && p.finish()) return core::Status::Ok;
  err = at(source, p.errorLine()) + p.reason();
  messages_.clear();
  by_id_.clear();
  diagnostics_.clear();
  skipped_.clear();
  return p.status();
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

namespace {

// Whether `s` is carried by a frame whose multiplexor reads `mux` (has_mux: it could be read).
bool present(const Signal& s, bool has_mux, uint64_t mux) {
  return s.multiplex_value < 0 || (has_mux && mux == static_cast<uint64_t>(s.multiplex_value));
}

}  // namespace

size_t decode(const Message& m, const Frame& f, std::vector<DecodedSignal>& out) {
  out.clear();
  if (f.rtr || f.error) return 0;
  bool has_mux = false;
  uint64_t mux = 0;
  if (m.multiplexor >= 0 && m.signals[size_t(m.multiplexor)].bytes_needed <= f.dlc) {
    has_mux = true;
    mux = extractRaw(m.signals[size_t(m.multiplexor)], f.data);
  }
  for (const auto& s : m.signals) {
    if (!s.supported || s.bytes_needed > f.dlc || !present(s, has_mux, mux)) continue;
    DecodedSignal d;
    d.signal = &s;
    d.raw = extractRaw(s, f.data);
    d.value = toPhysical(s, d.raw);
    out.push_back(d);
  }
  return out.size();
}

namespace {

struct Item {  // one signal to encode
  const Signal* signal;
  double value;
  const uint64_t* raw;  // its decoded bits, or nullptr
};

void prepare(const Message& m, Frame& f) {
  f.id = m.id;
  f.extended = m.extended;
  f.rtr = f.error = false;
  if (f.dlc < m.size) {
    f.dlc = static_cast<uint8_t>(m.size);
    if (m.size > kMaxClassicLen) f.fd = true;
  }
}

core::Status encodeOne(const Signal& s, double value, const uint64_t* decoded_raw, Frame& f, std::string& err) {
  if (!s.supported) {
    err = s.unsupported;
    return core::Status::Unsupported;
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
    return core::Status::InvalidArg;
  }
  if (s.bytes_needed > f.dlc) f.dlc = static_cast<uint8_t>(s.bytes_needed);
  insertRaw(s, raw, f.data);
  return core::Status::Ok;
}

// The multiplexor value the multiplexed signals among `items` need (-1: none), or InvalidArg when two differ.
core::Status neededMux(const Message& m, const std::vector<Item>& items, int64_t& need, std::string& err) {
  need = -1;
  const Signal* first = nullptr;
  for (const Item& it : items) {
    if (it.signal->multiplex_value < 0) continue;
    if (!first) {
      first = it.signal, need = it.signal->multiplex_value;
    } else if (it.signal->multiplex_value != need) {
      err = "message " + m.name + ": signals " + first->name + " (m" + std::to_string(need) + ") and " +
            it.signal->name + " (m" + std::to_string(it.signal->multiplex_value) + ") are never in one frame";
      return core::Status::InvalidArg;
    }
  }
  return core::Status::Ok;
}

core::Status encodeItems(const Message& m, const std::vector<Item>& items, Frame& f, std::string& err) {
  int64_t need = -1;
  if (const core::Status st = neededMux(m, items, need, err); st != core::Status::Ok) return st;
  prepare(m, f);
  bool mux_given = false;
  for (const Item& it : items) {
    if (const core::Status st = encodeOne(*it.signal, it.value, it.raw, f, err); st != core::Status::Ok) return st;
    mux_given = mux_given || (m.multiplexor >= 0 && it.signal == &m.signals[size_t(m.multiplexor)]);
  }
  if (need < 0) return core::Status::Ok;
  const Signal& mux = m.signals[size_t(m.multiplexor)];
  if (mux_given && extractRaw(mux, f.data) != static_cast<uint64_t>(need)) {
    err = "message " + m.name + ": multiplexor " + mux.name + " is given " + std::to_string(extractRaw(mux, f.data)) +
          " but the signals given need " + std::to_string(need);
    return core::Status::InvalidArg;
  }
  if (mux.bytes_needed > f.dlc) f.dlc = static_cast<uint8_t>(mux.bytes_needed);
  insertRaw(mux, static_cast<uint64_t>(need), f.data);
  return core::Status::Ok;
}

}  // namespace

core::Status encode(const Message& m, const std::vector<DecodedSignal>& values, Frame& f, std::string& err) {
  std::vector<Item> items;
  items.reserve(values.size());
  for (const auto& v : values) {
    if (!v.signal || v.signal < m.signals.data() || v.signal >= m.signals.data() + m.signals.size()) {
      err = "encode: a signal does not belong to message " + m.name;
      return core::Status::Misuse;
    }
    items.push_back({v.signal, v.value, &v.raw});
  }
  return encodeItems(m, items, f, err);
}

core::Status encode(const Message& m, const std::vector<std::pair<std::string, double>>& values, Frame& f,
                   std::string& err) {
  std::vector<Item> items;
  items.reserve(values.size());
  for (const auto& [name, value] : values) {
    const Signal* s = m.signal(name);
    if (!s) {
      err = "message " + m.name + " has no signal " + name;
      return core::Status::NotFound;
    }
    items.push_back({s, value, nullptr});
  }
  return encodeItems(m, items, f, err);
}

}  // namespace blvd::vehicle
