// A subset of the Vector DBC format, enough to decode and encode the signals of
// a vehicle's messages: BO_ (messages) and SG_ (signals) with Intel (@1) and
// Motorola (@0) byte order, signed (-) and unsigned (+) values, factor/offset,
// [min|max], unit and receivers; simple multiplexing (one `M` signal per
// message, `mN` signals decoded only while it holds N). VAL_ (value
// descriptions) and SIG_VALTYPE_ (IEEE float signals) are read when present;
// CM_, BA_DEF_, BA_, SIG_GROUP_, VAL_TABLE_ and every other statement are
// skipped, including multi-line quoted strings.
//
// Files as real projects ship them (opendbc's, for one) hold messages no decoder
// can use: ids above 0x7FF without the extended bit, extended multiplexing
// (`mNM`, SG_MUL_VAL_), sizes past 64 bytes, a malformed signal line. By default
// such a message is skipped whole, never in part: Database::skipped() and
// diagnostics() name file, line and reason ("f.dbc:12: message X skipped: ..."),
// and the rest of the file loads. DbcOptions::strict makes the first of them
// fail the load instead, with "file:line: reason" (core::Status::Corrupt for a
// syntax error, Unsupported for what is valid DBC but not decoded). A file in
// which no message could be used fails either way.
//
// Bit numbering is the DBC's: bit b is bit (b % 8) of byte (b / 8). An Intel
// signal's start bit is its least significant bit, and it grows towards higher
// bit numbers; a Motorola signal's start bit is its most significant bit, and it
// continues from bit 0 of a byte to bit 7 of the next byte (the "sawtooth").
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/status.h"
#include "vehicle/frame.h"

namespace blvd::vehicle {

enum class ByteOrder : uint8_t { Intel, Motorola };  // @1 little endian, @0 big endian
enum class ValueType : uint8_t { Integer, Float32, Float64 };  // SIG_VALTYPE_ 0 / 1 / 2

struct Signal {
  std::string name;
  uint16_t start_bit = 0;  // as written: Intel LSB, Motorola MSB
  uint16_t length = 0;     // 1..64 bits
  ByteOrder order = ByteOrder::Intel;
  bool is_signed = false;
  ValueType type = ValueType::Integer;
  double factor = 1, offset = 0;
  double minimum = 0, maximum = 0;  // as declared; advisory, not enforced (many DBCs get them wrong)
  std::string unit;
  std::vector<std::string> receivers;
  bool multiplexor = false;        // 'M'
  int32_t multiplex_value = -1;    // 'm12' -> 12: present while the multiplexor's raw value is 12; -1 always
  bool supported = true;
  std::string unsupported;         // why, when !supported
  uint32_t line = 0;
  uint16_t bytes_needed = 0;       // the frame must carry this many bytes to hold the signal
  std::vector<std::pair<int64_t, std::string>> values;  // VAL_ descriptions, in file order

  // The description VAL_ gives for a raw value, or nullptr.
  const std::string* describe(int64_t raw) const;
};

struct Message {
  uint32_t id = 0;  // without the extended flag
  bool extended = false;
  std::string name;
  uint32_t size = 0;  // bytes
  std::string transmitter;
  std::vector<Signal> signals;
  int32_t multiplexor = -1;  // index in signals of the 'M' signal; -1 without multiplexing
  uint32_t line = 0;

  const Signal* signal(std::string_view signal_name) const;
};

// A message the decoder cannot use, left out of the database.
struct SkippedMessage {
  std::string name;  // "" when the BO_ line did not give one
  uint32_t line = 0;   // where the reason lies (the BO_, SG_ or SG_MUL_VAL_ line)
  std::string reason;
};

struct DecodedSignal {
  const Signal* signal = nullptr;
  uint64_t raw = 0;    // the bits as stored (not sign-extended)
  double value = 0;    // physical value: raw (sign-extended or as float) * factor + offset
};

struct DbcOptions {
  bool strict = false;  // fail the load at the first message or signal that would be skipped or left out
};

class Database {
 public:
  // Parses DBC text; `source` names it in messages. On failure the database is
  // empty and `err` is "source:line: reason". core::Status::Corrupt for a syntax error.
  core::Status parse(std::string_view text, const std::string& source, std::string& err,
                    const DbcOptions& opt = DbcOptions{});
  // Reads and parses a file. core::Status::Io when it cannot be read.
  core::Status load(const std::string& path, std::string& err, const DbcOptions& opt = DbcOptions{});

  const std::vector<Message>& messages() const { return messages_; }
  const Message* find(uint32_t id, bool extended) const;
  const Message* find(const Frame& f) const { return f.error || f.rtr ? nullptr : find(f.id, f.extended); }
  const Message* findByName(std::string_view name) const;
  // Non-fatal findings, one line each, "source:line: text", in file order.
  const std::vector<std::string>& diagnostics() const { return diagnostics_; }
  // The messages left out, in file order (each also has its line in diagnostics()).
  const std::vector<SkippedMessage>& skipped() const { return skipped_; }
  const std::string& source() const { return source_; }

 private:
  class Parser;  // dbc.cpp: one text being read
  std::vector<Message> messages_;
  std::unordered_map<uint32_t, size_t> by_id_;  // id | 0x80000000 for extended ids
  std::vector<std::string> diagnostics_;
  std::vector<SkippedMessage> skipped_;
  std::string source_;
};

// The raw bits of `s` in `data`, which must hold at least s.bytes_needed bytes.
uint64_t extractRaw(const Signal& s, const uint8_t* data);
// Writes the low s.length bits of `raw` into `data`, leaving every other bit alone.
void insertRaw(const Signal& s, uint64_t raw, uint8_t* data);
// raw -> physical value.
double toPhysical(const Signal& s, uint64_t raw);
// physical value -> raw bits, rounding to the nearest step. False when the value
// is not finite or does not fit the signal's bits.
bool toRaw(const Signal& s, double value, uint64_t& raw);

// Decodes the supported signals of `m` that lie inside f's payload (a frame
// shorter than the message loses only the signals past its end) into `out`
// (cleared first): of the multiplexed ones, those the multiplexor's value
// selects (none when the multiplexor lies past the end). Returns the number decoded.
size_t decode(const Message& m, const Frame& f, std::vector<DecodedSignal>& out);

// Writes the given signals into `f`: sets f's id, extended flag and (when it is
// shorter) length from `m`, and changes only the bits of those signals, so
// encode(m, decode(m, f), f2) reproduces every signal bit of f in f2.
// Each entry's `signal` must point into m.signals (else core::Status::Misuse). `value` is
// encoded; when it is exactly the value `raw` decodes to, `raw` is written as is.
// Multiplexed signals set the multiplexor to their value; given with the
// multiplexor, they must agree with it and with each other.
// core::Status::InvalidArg with `err` naming the signal when a value does not fit
// or the multiplexor values disagree; core::Status::Unsupported for a signal left out at load.
core::Status encode(const Message& m, const std::vector<DecodedSignal>& values, Frame& f, std::string& err);
// The same, signals given by name. core::Status::NotFound for a name m lacks.
core::Status encode(const Message& m, const std::vector<std::pair<std::string, double>>& values, Frame& f,
                   std::string& err);

}  // namespace blvd::vehicle
