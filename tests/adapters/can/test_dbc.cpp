// DBC subset: byte-order edge cases (signals crossing bytes, Motorola start
// bits, 64-bit signals, signs) checked against an independent formulation,
// simple multiplexing, messages skipped (or refused when strict) naming file,
// line and reason, the opendbc files and the field cases (every message
// round-trips random values), and encode(decode(frame)) == frame on a real log.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <sstream>

#include "can/candump.h"
#include "vehicle/dbc.h"
#include "can_test_util.h"

namespace blvd::can {
namespace {

// The DBC subset and the profiles are the SDK's sdk/vehicle module; the candump
// reader that feeds these tests is the adapter's.
using namespace blvd::vehicle;

Database parseDbc(const std::string& text) {
  Database db;
  std::string err;
  EXPECT_EQ(db.parse(text, "test.dbc", err), blvd::core::Status::Ok) << err;
  return db;
}

std::string parseError(const std::string& text, blvd::core::Status want = blvd::core::Status::Corrupt) {
  Database db;
  std::string err;
  DbcOptions strict;
  strict.strict = true;
  EXPECT_EQ(db.parse(text, "bad.dbc", err, strict), want) << text;
  EXPECT_TRUE(db.messages().empty());
  return err;
}

Frame frameOf(uint32_t id, std::initializer_list<uint8_t> bytes) {
  Frame f;
  f.id = id;
  for (uint8_t b : bytes) f.data[f.dlc++] = b;
  return f;
}

double value(const Message& m, const Frame& f, const char* name) {
  std::vector<DecodedSignal> out;
  decode(m, f, out);
  for (const auto& d : out)
    if (d.signal->name == name) return d.value;
  ADD_FAILURE() << name << " not decoded";
  return 0;
}

// Independent formulation of the two byte orders. Intel: the payload as one
// little-endian integer, the signal `length` bits from `start` up. Motorola:
// the payload as a big-endian bit stream (bit 7 of byte 0 first); the start
// bit's position in that stream is (start / 8) * 8 + 7 - start % 8, and the
// signal is the `length` bits from there on, most significant first.
uint64_t referenceRaw(const uint8_t* data, unsigned start, unsigned length, bool motorola) {
  uint64_t v = 0;
  for (unsigned i = 0; i < length; ++i) {
    unsigned byte, bit;
    if (!motorola) {
      const unsigned b = start + (length - 1 - i);  // MSB first
      byte = b / 8, bit = b % 8;
    } else {
      const unsigned s = (start / 8) * 8 + 7 - start % 8 + i;
      byte = s / 8, bit = 7 - s % 8;
    }
    v = (v << 1) | ((data[byte] >> bit) & 1u);
  }
  return v;
}

const char* kEdgeDbc = R"(VERSION ""


NS_ :
    NS_DESC_
    CM_
    BO_
    SG_
    VAL_

BS_:

BU_: ECU GW

BO_ 256 EDGES: 8 ECU
 SG_ IntelCross : 4|12@1+ (1,0) [0|4095] "" GW
 SG_ IntelSigned : 16|8@1- (0.5,0) [-64|63.5] "m" GW,ECU
 SG_ IntelTop : 63|1@1+ (1,0) [0|1] "" Vector__XXX
 SG_ MotoCross : 27|12@0+ (1,0) [0|4095] "" GW
 SG_ MotoSawtooth : 40|2@0+ (1,0) [0|3] "" GW
 SG_ MotoFraction : 55|4@0- (0.1,0) [-0.7|0.7] "deg" GW

BO_ 257 WIDE: 8 ECU
 SG_ Intel64 : 0|64@1+ (1,0) [0|0] "" GW

BO_ 258 WIDE_BE: 8 ECU
 SG_ Moto64 : 7|64@0- (1,0) [0|0] "" GW

BO_ 2147484159 EXTENDED: 3 GW
 SG_ Speed : 7|16@0+ (0.01,-67.67) [0|250] "km/h" ECU
 SG_ Gear : 23|4@0+ (1,0) [0|15] "" ECU

BO_ 259 MUXED: 8 ECU
 SG_ Mode M : 0|2@1+ (1,0) [0|3] "" GW
 SG_ A m0 : 8|8@1+ (1,0) [0|255] "" GW
 SG_ B m1 : 8|8@1+ (1,0) [0|255] "" GW
 SG_ Plain : 16|8@1+ (1,0) [0|255] "" GW

BO_ 260 FLOATS: 8 ECU
 SG_ F32 : 0|32@1- (1,0) [0|0] "" GW
 SG_ F32Scaled : 32|32@1- (2,1) [0|0] "" GW

BO_ 3221225472 VECTOR__INDEPENDENT_SIG_MSG: 0 Vector__XXX
 SG_ Orphan : 0|8@1+ (1,0) [0|0] "" Vector__XXX

CM_ "A comment that runs
over three lines, with BO_ 999 FAKE: 8 X and
SG_ inside";
CM_ SG_ 256 IntelCross "escaped \" quote
and a second line";
BA_DEF_ SG_  "GenSigStartValue" INT 0 10000;
VAL_ 2147484159 Gear 0 "P" 1 "R" 2 "N" 3 "D" ;
VAL_ 999 Nothing 0 "x" ;
SIG_VALTYPE_ 260 F32 : 1;
SIG_VALTYPE_ 260 F32Scaled : 1;
)";

TEST(Dbc, ParsesTheEdgeCaseFile) {
  const Database db = parseDbc(kEdgeDbc);
  ASSERT_EQ(db.messages().size(), 6u);  // the VECTOR__INDEPENDENT_SIG_MSG container is not a frame
  EXPECT_EQ(db.findByName("FAKE"), nullptr);  // text inside a CM_ string is not a statement
  const Message* e = db.find(0x100, false);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->name, "EDGES");
  EXPECT_EQ(e->size, 8u);
  EXPECT_EQ(e->transmitter, "ECU");
  ASSERT_EQ(e->signals.size(), 6u);
  const Signal* s = e->signal("IntelSigned");
  ASSERT_NE(s, nullptr);
  EXPECT_TRUE(s->is_signed);
  EXPECT_EQ(s->order, ByteOrder::Intel);
  EXPECT_EQ(s->factor, 0.5);
  EXPECT_EQ(s->minimum, -64);
  EXPECT_EQ(s->maximum, 63.5);
  EXPECT_EQ(s->unit, "m");
  EXPECT_EQ(s->receivers, (std::vector<std::string>{"GW", "ECU"}));
  EXPECT_EQ(s->line, 17u);

  const Message* x = db.find(0x1FF, true);
  ASSERT_NE(x, nullptr);
  EXPECT_EQ(x->name, "EXTENDED");
  EXPECT_EQ(db.find(0x1FF, false), nullptr);
  const Signal* gear = x->signal("Gear");
  ASSERT_NE(gear, nullptr);
  ASSERT_EQ(gear->values.size(), 4u);
  ASSERT_NE(gear->describe(3), nullptr);
  EXPECT_EQ(*gear->describe(3), "D");
}

TEST(Dbc, IntelAndMotorolaAcrossBytes) {
  const Database db = parseDbc(kEdgeDbc);
  const Message& m = *db.findByName("EDGES");
  //            byte: 0     1     2     3     4     5     6     7
  const Frame f = frameOf(0x100, {0xA5, 0xBC, 0xFE, 0x5A, 0x81, 0xF0, 0x00, 0x80});
  // Intel 4|12: the high nibble of byte 0, then byte 1 above it.
  EXPECT_EQ(value(m, f, "IntelCross"), 0xBCA);
  // Intel signed 16|8 = 0xFE = -2, times 0.5.
  EXPECT_EQ(value(m, f, "IntelSigned"), -1.0);
  // Intel 63|1: the top bit of byte 7.
  EXPECT_EQ(value(m, f, "IntelTop"), 1.0);
  // Motorola 27|12: MSB is bit 3 of byte 3, so the low nibble of byte 3 then byte 4.
  EXPECT_EQ(value(m, f, "MotoCross"), 0xA81);
  // Motorola 40|2: bit 0 of byte 5, then on to bit 7 of byte 6 (the sawtooth).
  EXPECT_EQ(value(m, f, "MotoSawtooth"), 0.0 * 2 + 0);  // byte5 bit0 = 0, byte6 bit7 = 0
  Frame g = f;
  g.data[5] = 0x01;
  g.data[6] = 0x80;
  EXPECT_EQ(value(m, g, "MotoSawtooth"), 3.0);
  g.data[6] = 0x00;
  EXPECT_EQ(value(m, g, "MotoSawtooth"), 2.0);
  // Motorola signed 55|4 (Toyota's STEER_FRACTION layout): the high nibble of byte 6.
  g.data[6] = 0xF0;
  EXPECT_NEAR(value(m, g, "MotoFraction"), -0.1, 1e-12);
  g.data[6] = 0x70;
  EXPECT_NEAR(value(m, g, "MotoFraction"), 0.7, 1e-12);
}

TEST(Dbc, SixtyFourBitSignals) {
  const Database db = parseDbc(kEdgeDbc);
  const Frame f = frameOf(0x101, {0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x88});
  std::vector<DecodedSignal> out;
  ASSERT_EQ(decode(*db.findByName("WIDE"), f, out), 1u);
  EXPECT_EQ(out[0].raw, 0x8807060504030201ull);
  Frame g = f;
  g.id = 0x102;
  ASSERT_EQ(decode(*db.findByName("WIDE_BE"), g, out), 1u);
  EXPECT_EQ(out[0].raw, 0x0102030405060788ull);
  // Both round-trip exactly, though a double cannot hold every 64-bit value.
  Frame back;
  std::string err;
  ASSERT_EQ(encode(*db.findByName("WIDE_BE"), out, back, err), blvd::core::Status::Ok) << err;
  EXPECT_EQ(std::memcmp(back.data, g.data, 8), 0);
}

TEST(Dbc, RandomSignalsMatchTheIndependentFormulation) {
  std::mt19937 rng(1234);
  for (int trial = 0; trial < 20000; ++trial) {
    Signal s;
    s.name = "S";
    s.order = rng() % 2 ? ByteOrder::Motorola : ByteOrder::Intel;
    s.length = static_cast<uint16_t>(1 + rng() % 64);
    s.start_bit = static_cast<uint16_t>(rng() % 64);
    // Keep the signal inside 8 bytes.
    const unsigned begin =
        s.order == ByteOrder::Intel ? s.start_bit : (s.start_bit / 8u) * 8u + 7u - s.start_bit % 8u;
    if (begin + s.length > 64) continue;
    uint8_t data[64] = {};
    for (int i = 0; i < 8; ++i) data[i] = static_cast<uint8_t>(rng());
    const uint64_t want = referenceRaw(data, s.start_bit, s.length, s.order == ByteOrder::Motorola);
    ASSERT_EQ(extractRaw(s, data), want) << "start " << s.start_bit << " len " << s.length;
    // insertRaw writes exactly those bits and no others.
    uint8_t copy[64];
    std::memcpy(copy, data, sizeof copy);
    const uint64_t mask = s.length == 64 ? ~0ull : (1ull << s.length) - 1;
    const uint64_t other = rng() & mask;
    insertRaw(s, other, copy);
    ASSERT_EQ(extractRaw(s, copy), other);
    insertRaw(s, want, copy);
    ASSERT_EQ(std::memcmp(copy, data, sizeof copy), 0);
  }
}

TEST(Dbc, SimpleMultiplexingDecodesTheSelectedSignals) {
  const Database db = parseDbc(kEdgeDbc);
  const Message& m = *db.findByName("MUXED");
  ASSERT_EQ(m.multiplexor, 0);
  EXPECT_EQ(m.signal("A")->multiplex_value, 0);
  EXPECT_TRUE(m.signal("A")->supported);
  EXPECT_TRUE(db.skipped().empty());
  const Frame f = frameOf(0x103, {0x01, 0x22, 0x33, 0, 0, 0, 0, 0});
  std::vector<DecodedSignal> out;
  ASSERT_EQ(decode(m, f, out), 3u);  // Mode 1 selects B, not A
  EXPECT_EQ(out[0].signal->name, "Mode");
  EXPECT_EQ(out[0].value, 1);
  EXPECT_EQ(out[1].signal->name, "B");
  EXPECT_EQ(out[1].value, 0x22);
  EXPECT_EQ(out[2].signal->name, "Plain");
  EXPECT_EQ(out[2].value, 0x33);
  // A frame too short for the multiplexor carries none of the multiplexed signals.
  EXPECT_EQ(decode(m, frameOf(0x103, {}), out), 0u);
}

TEST(Dbc, EncodingAMultiplexedSignalSetsItsMultiplexor) {
  const Database db = parseDbc(kEdgeDbc);
  const Message& m = *db.findByName("MUXED");
  Frame g;
  std::string err;
  ASSERT_EQ(encode(m, {{"A", 7.0}, {"Plain", 9.0}}, g, err), blvd::core::Status::Ok) << err;
  EXPECT_EQ(g.data[0] & 3, 0);
  EXPECT_EQ(value(m, g, "A"), 7);
  ASSERT_EQ(encode(m, {{"B", 5.0}}, g, err), blvd::core::Status::Ok) << err;
  EXPECT_EQ(g.data[0] & 3, 1);
  EXPECT_EQ(value(m, g, "B"), 5);
  EXPECT_EQ(encode(m, {{"Mode", 1.0}, {"B", 5.0}}, g, err), blvd::core::Status::Ok) << err;
  // Never in one frame: two multiplexor values, or a multiplexor that disagrees.
  EXPECT_EQ(encode(m, {{"A", 1.0}, {"B", 2.0}}, g, err), blvd::core::Status::InvalidArg);
  EXPECT_EQ(err, "message MUXED: signals A (m0) and B (m1) are never in one frame");
  EXPECT_EQ(encode(m, {{"Mode", 0.0}, {"B", 2.0}}, g, err), blvd::core::Status::InvalidArg);
  EXPECT_EQ(err, "message MUXED: multiplexor Mode is given 0 but the signals given need 1");
}

TEST(Dbc, FloatSignals) {
  const Database db = parseDbc(kEdgeDbc);
  const Message& m = *db.findByName("FLOATS");
  EXPECT_EQ(m.signal("F32")->type, ValueType::Float32);
  Frame f;
  std::string err;
  ASSERT_EQ(encode(m, {{"F32", -1.5}, {"F32Scaled", 7.0}}, f, err), blvd::core::Status::Ok) << err;
  EXPECT_EQ(f.data[3], 0xBF);  // -1.5f = 0xBFC00000, little endian
  EXPECT_EQ(f.data[2], 0xC0);
  EXPECT_EQ(value(m, f, "F32"), -1.5);
  EXPECT_EQ(value(m, f, "F32Scaled"), 7.0);
}

TEST(Dbc, ShortFramesLoseOnlyTheSignalsPastTheirEnd) {
  const Database db = parseDbc(kEdgeDbc);
  const Message& m = *db.findByName("EXTENDED");
  Frame f = frameOf(0x1FF, {0x1A, 0x6F});  // Speed only; Gear is in byte 2
  f.extended = true;
  std::vector<DecodedSignal> out;
  ASSERT_EQ(decode(m, f, out), 1u);
  EXPECT_EQ(out[0].signal->name, "Speed");
  EXPECT_NEAR(out[0].value, 0x1A6F * 0.01 - 67.67, 1e-9);
  f.rtr = true;
  EXPECT_EQ(decode(m, f, out), 0u);
}

TEST(Dbc, EncodeByNameAndRange) {
  const Database db = parseDbc(kEdgeDbc);
  const Message& m = *db.findByName("EXTENDED");
  Frame f;
  std::string err;
  ASSERT_EQ(encode(m, {{"Speed", 50.0}, {"Gear", 3}}, f, err), blvd::core::Status::Ok) << err;
  EXPECT_TRUE(f.extended);
  EXPECT_EQ(f.id, 0x1FFu);
  EXPECT_EQ(f.dlc, 3);
  EXPECT_NEAR(value(m, f, "Speed"), 50.0, 1e-9);
  EXPECT_EQ(value(m, f, "Gear"), 3);
  EXPECT_EQ(encode(m, {{"Gear", 16}}, f, err), blvd::core::Status::InvalidArg);
  EXPECT_NE(err.find("signal Gear"), std::string::npos) << err;
  EXPECT_EQ(encode(m, {{"Speed", -70}}, f, err), blvd::core::Status::InvalidArg);
  EXPECT_EQ(encode(m, {{"Nope", 1}}, f, err), blvd::core::Status::NotFound);
  EXPECT_EQ(err, "message EXTENDED has no signal Nope");
}

TEST(Dbc, StrictErrorsNameFileAndLine) {
  EXPECT_EQ(parseError("BO_ 1 A: 8 X\n SG_ S : 0|8@2+ (1,0) [0|1] \"\" X\n"),
            "bad.dbc:2: message A: signal S: byte order must be @0 or @1");
  EXPECT_EQ(parseError("\n\n SG_ S : 0|8@1+ (1,0) [0|1] \"\" X\n"), "bad.dbc:3: SG_ outside a BO_ message");
  EXPECT_EQ(parseError("BO_ 1 A: 8 X\n SG_ S : 0|8@1+ (1,0 [0|1] \"\" X\n"),
            "bad.dbc:2: message A: signal S: expected (FACTOR,OFFSET)");
  EXPECT_EQ(parseError("BO_ 1 A: 8 X\n SG_ S : 0|65@1+ (1,0) [0|1] \"\" X\n"),
            "bad.dbc:2: message A: signal S: length 65 is not 1..64 bits");
  EXPECT_EQ(parseError("BO_ 1 A: 8 X\n SG_ S : 500|16@1+ (1,0) [0|1] \"\" X\n"),
            "bad.dbc:2: message A: signal S: bits 500|16 run outside a 64-byte frame");
  EXPECT_EQ(parseError("BO_ 1 A: 8 X\n SG_ S : 0|8@1+ (1,0) [0|1] \"unterminated X\n"),
            "bad.dbc:2: message A: signal S: expected \"UNIT\"");
  EXPECT_EQ(parseError("BO_ 1 A: 8 X\nBO_ 1 B: 8 X\n"), "bad.dbc:2: message B: id 1 already used by A (line 1)");
  EXPECT_EQ(parseError("BO_ 2048 A: 8 X\n"), "bad.dbc:1: message A: id 2048 exceeds 0x7FF (extended ids set bit 31)");
  EXPECT_EQ(parseError("BO_ 1 A: 65 X\n"), "bad.dbc:1: message A: size 65 exceeds 64 bytes");
  EXPECT_EQ(parseError("BO_ 1 A: 8 X\n SG_ S : 0|8@1+ (1,0) [0|1] \"\" X\n SG_ S : 8|8@1+ (1,0) [0|1] \"\" X\n"),
            "bad.dbc:3: message A: signal S declared twice (first at line 2)");
  EXPECT_EQ(parseError("BO_ 1 A: 8 X\n SG_ S x7 : 0|8@1+ (1,0) [0|1] \"\" X\n"),
            "bad.dbc:2: message A: bad multiplexer indicator 'x7' for signal S");
  EXPECT_EQ(parseError("BO_ 1 A: 8 X\n SG_ S m1M : 0|8@1+ (1,0) [0|1] \"\" X\n SG_ M0 M : 8|8@1+ (1,0) [0|1] \"\" X\n",
                       blvd::core::Status::Unsupported),
            "bad.dbc:1: message A: extended multiplexing: signal S is multiplexed and a multiplexor");
  EXPECT_EQ(parseError("BO_ X A: 8 X\n"), "bad.dbc:1: BO_ without a numeric id");
  Database db;
  std::string err;
  EXPECT_EQ(db.load("/nonexistent/x.dbc", err), blvd::core::Status::Io);
  EXPECT_EQ(err.rfind("/nonexistent/x.dbc: cannot open", 0), 0u) << err;
}

TEST(Dbc, ByDefaultAMessageItCannotUseIsSkippedAndTheRestLoads) {
  const Database db = parseDbc("BO_ 1 A: 8 X\n SG_ S : 0|8@2+ (1,0) [0|1] \"\" X\n SG_ T : 8|8@1+ (1,0) [0|1] \"\" X\n"
                               "BO_ 2048 BIG: 8 X\n SG_ U : 0|8@1+ (1,0) [0|1] \"\" X\n"
                               "BO_ 2 B: 8 X\n SG_ V : 0|8@1+ (1,0) [0|255] \"\" X\n");
  ASSERT_EQ(db.messages().size(), 1u);
  EXPECT_EQ(db.messages()[0].name, "B");
  EXPECT_EQ(db.find(2, false), &db.messages()[0]);
  EXPECT_EQ(db.find(1, false), nullptr);  // never a message in part
  ASSERT_EQ(db.skipped().size(), 2u);
  EXPECT_EQ(db.skipped()[0].name, "A");
  EXPECT_EQ(db.skipped()[0].line, 2u);
  EXPECT_EQ(db.skipped()[1].reason, "id 2048 exceeds 0x7FF (extended ids set bit 31)");
  ASSERT_EQ(db.diagnostics().size(), 2u);
  EXPECT_EQ(db.diagnostics()[0], "test.dbc:2: message A skipped: signal S: byte order must be @0 or @1");
  EXPECT_EQ(db.diagnostics()[1], "test.dbc:4: message BIG skipped: id 2048 exceeds 0x7FF (extended ids set bit 31)");
  // A file of which nothing could be used fails, naming the first reason.
  Database none;
  std::string err;
  EXPECT_EQ(none.parse("BO_ 4000 BIG: 8 X\n", "none.dbc", err), blvd::core::Status::Corrupt);
  EXPECT_EQ(err, "none.dbc:1: no message could be used (1 skipped; the first: id 4000 exceeds 0x7FF (extended ids set bit 31))");
}

TEST(Dbc, LocaleIndependentNumbersAndCrlf) {
  const Database db = parseDbc("BO_ 1 A: 8 X\r\n SG_ S : 0|16@1- (+1E-002,-1.5e1) [-3.2e2|+320] \"\" X\r\n");
  const Signal* s = db.findByName("A")->signal("S");
  ASSERT_NE(s, nullptr);
  EXPECT_DOUBLE_EQ(s->factor, 0.01);
  EXPECT_DOUBLE_EQ(s->offset, -15);
  EXPECT_DOUBLE_EQ(s->minimum, -320);
}

// A raw value of `s` whose physical value is finite and inside [minimum, maximum]
// when the DBC declares a range (many declare [0|0]: none).
uint64_t randomRaw(const Signal& s, std::mt19937_64& rng) {
  const uint64_t mask = s.length == 64 ? ~0ull : (1ull << s.length) - 1;
  const bool ranged = s.minimum < s.maximum;
  uint64_t raw = 0;
  for (int tries = 0; tries < 64; ++tries) {
    raw = rng() & mask;
    const double v = toPhysical(s, raw);
    if (std::isfinite(v) && (!ranged || (v >= s.minimum && v <= s.maximum))) return raw;
  }
  if (ranged && toRaw(s, s.minimum, raw)) return raw;
  return 0;
}

// The signals a frame of `m` carries under multiplexor value `mux` (-1: the
// plain ones), at random values, encoded by physical value and decoded again.
// Real files overlay signals on the same bits (a byte and a bit of it): in a
// random order, each signal whose bits are still free; over several trips every one.
void roundTrip(const Message& m, int64_t mux, std::mt19937_64& rng) {
  std::vector<size_t> order(m.signals.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::shuffle(order.begin(), order.end(), rng);
  uint8_t used[64] = {};
  if (m.multiplexor >= 0) insertRaw(m.signals[size_t(m.multiplexor)], ~0ull, used);
  std::vector<std::pair<std::string, double>> named;
  for (const size_t i : order) {
    const Signal& s = m.signals[i];
    if (!s.supported || int32_t(i) == m.multiplexor || (s.multiplex_value >= 0 && s.multiplex_value != mux)) continue;
    uint8_t bits[64] = {};
    insertRaw(s, ~0ull, bits);
    bool free = true;
    for (int b = 0; b < 64; ++b) free = free && !(bits[b] & used[b]);
    if (!free) continue;
    for (int b = 0; b < 64; ++b) used[b] |= bits[b];
    named.emplace_back(s.name, toPhysical(s, randomRaw(s, rng)));
  }
  Frame f;
  std::string err;
  ASSERT_EQ(encode(m, named, f, err), blvd::core::Status::Ok) << m.name << ": " << err;
  std::vector<DecodedSignal> out;
  decode(m, f, out);
  for (const auto& [name, v] : named) {
    const auto it = std::find_if(out.begin(), out.end(), [&](const DecodedSignal& d) { return d.signal->name == name; });
    ASSERT_NE(it, out.end()) << m.name << "." << name << " not decoded (multiplexor " << mux << ")";
    EXPECT_EQ(it->value, v) << m.name << "." << name;
  }
  if (mux < 0) return;
  const Signal* sel = &m.signals[size_t(m.multiplexor)];  // set by encode
  const auto it = std::find_if(out.begin(), out.end(), [&](const DecodedSignal& d) { return d.signal == sel; });
  ASSERT_NE(it, out.end()) << m.name;
  EXPECT_EQ(it->raw, uint64_t(mux)) << m.name;
}

struct CorpusFile {
  const char* file;  // under tests/data/can
  size_t messages, skipped;
};

// The opendbc files and the field cases: each loads, skips what it must (named,
// with a line), and every message it keeps round-trips random in-range values
// under every multiplexor value its signals name.
TEST(Dbc, FieldCorpusLoadsSkipsWhatItMustAndRoundTrips) {
  std::mt19937_64 rng(27);
  size_t trips = 0;
  for (const CorpusFile& want : {CorpusFile{"dbc/toyota_new_mc_pt_generated.dbc", 55, 0},
                                 CorpusFile{"dbc/vw_mqb.dbc", 113, 0}, CorpusFile{"dbc/hyundai_2015_ccan.dbc", 113, 0},
                                 CorpusFile{"dbc_cases/big_ids.dbc", 4, 2}, CorpusFile{"dbc_cases/multiplexed.dbc", 2, 4},
                                 CorpusFile{"dbc_cases/broken_lines.dbc", 2, 6}}) {
    SCOPED_TRACE(want.file);
    Database db;
    std::string err;
    ASSERT_EQ(db.load(test::dataPath(want.file), err), blvd::core::Status::Ok) << err;
    EXPECT_EQ(db.messages().size(), want.messages);
    EXPECT_EQ(db.skipped().size(), want.skipped);
    for (const auto& sk : db.skipped()) EXPECT_GT(sk.line, 0u) << sk.reason;
    for (const auto& m : db.messages()) {
      std::vector<int64_t> muxes{-1};
      for (const auto& s : m.signals)
        if (s.multiplex_value >= 0 && std::find(muxes.begin(), muxes.end(), s.multiplex_value) == muxes.end())
          muxes.push_back(s.multiplex_value);
      if (m.multiplexor >= 0) muxes.erase(muxes.begin());
      for (const int64_t mux : muxes)
        for (int k = 0; k < 4; ++k, ++trips) roundTrip(m, mux, rng);
    }
    // Strict refuses the same file at its first skipped message.
    DbcOptions strict;
    strict.strict = true;
    Database sdb;
    EXPECT_EQ(sdb.load(test::dataPath(want.file), err, strict) == blvd::core::Status::Ok, want.skipped == 0) << err;
  }
  std::printf("%zu message round trips\n", trips);
}

TEST(Dbc, FieldCasesSayWhyEachMessageIsSkipped) {
  Database db;
  std::string err;
  ASSERT_EQ(db.load(test::dataPath("dbc_cases/multiplexed.dbc"), err), blvd::core::Status::Ok) << err;
  std::vector<std::string> why;
  for (const auto& sk : db.skipped()) why.push_back(sk.name + " @" + std::to_string(sk.line) + ": " + sk.reason);
  EXPECT_EQ(why, (std::vector<std::string>{
                     "DIAG_EXTENDED @25: extended multiplexing (SG_MUL_VAL_, line 44)",
                     "TWO_MUXES @30: more than one multiplexor (A, B)",
                     "ORPHAN_MUX @35: multiplexed signal D without a multiplexor",
                     "MUL_VAL_ONLY @38: extended multiplexing (SG_MUL_VAL_, line 45)"}));
  const Message& radar = *db.findByName("RADAR_TRACK");
  const Frame f = frameOf(1024, {2, 0x50, 0x12, 0x34, 0, 0, 0, 0});
  std::vector<DecodedSignal> out;
  decode(radar, f, out);
  ASSERT_EQ(out.size(), 3u);  // TRACK_ID, STATUS, RANGE_2
  EXPECT_EQ(out[2].signal->name, "RANGE_2");
  EXPECT_DOUBLE_EQ(out[2].value, 0x1234 * 0.01);

  Database big;
  ASSERT_EQ(big.load(test::dataPath("dbc_cases/big_ids.dbc"), err), blvd::core::Status::Ok) << err;
  EXPECT_EQ(big.diagnostics().at(0), test::dataPath("dbc_cases/big_ids.dbc") +
                                         ":61: message LKAS_HUD_A skipped: id 13274 exceeds 0x7FF (extended ids set bit 31)");
  EXPECT_EQ(*big.findByName("POWERTRAIN_DATA")->signal("GEAR")->describe(3), "D");
}

TEST(Dbc, OpendbcFilesKeepTheirSignals) {
  for (const auto& [file, signals] : {std::pair<const char*, size_t>{"toyota_new_mc_pt_generated.dbc", 330},
                                      {"vw_mqb.dbc", 1348}, {"hyundai_2015_ccan.dbc", 1154}}) {
    Database db;
    std::string err;
    ASSERT_EQ(db.load(test::dataPath(std::string("dbc/") + file), err), blvd::core::Status::Ok) << err;
    size_t n = 0;
    for (const auto& m : db.messages()) n += m.signals.size();
    EXPECT_EQ(n, signals) << file;
  }
  Database vw;
  std::string err;
  ASSERT_EQ(vw.load(test::dataPath("dbc/vw_mqb.dbc"), err), blvd::core::Status::Ok);
  const Message& vin = *vw.findByName("VIN_01");
  const Signal* ks = vin.signal("KS_Geheimnis_1");
  ASSERT_NE(ks, nullptr);
  EXPECT_TRUE(ks->supported);
  ASSERT_GE(vin.multiplexor, 0);
  EXPECT_EQ(ks->line, 1243u);
  // The rest of the file is usable: the VW profile's signals, with their sign bits.
  const Message* esp02 = vw.find(0x101, false);
  ASSERT_NE(esp02, nullptr);
  EXPECT_EQ(esp02->name, "ESP_02");
  ASSERT_NE(esp02->signal("ESP_Gierrate"), nullptr);
  ASSERT_NE(esp02->signal("ESP_VZ_Gierrate"), nullptr);
  EXPECT_EQ(esp02->signal("ESP_Gierrate")->length, 14);
  EXPECT_EQ(esp02->signal("ESP_Gierrate")->factor, 0.01);

  Database toyota;
  ASSERT_EQ(toyota.load(test::dataPath("dbc/toyota_new_mc_pt_generated.dbc"), err), blvd::core::Status::Ok);
  const Signal* steer = toyota.find(0x25, false)->signal("STEER_ANGLE");
  EXPECT_EQ(steer->order, ByteOrder::Motorola);
  EXPECT_TRUE(steer->is_signed);
  EXPECT_EQ(steer->start_bit, 3);
  EXPECT_EQ(steer->length, 12);
  EXPECT_EQ(steer->factor, 1.5);
  const Signal* gear = toyota.find(0x3BC, false)->signal("GEAR");
  ASSERT_NE(gear->describe(32), nullptr);
  EXPECT_EQ(*gear->describe(32), "P");
}

// Every frame of the comma2k19 log whose id the Toyota DBC knows: decode, encode
// the physical values into a zeroed frame, and the signal bits come back equal.
TEST(Dbc, EncodeDecodeRoundTripOnComma2k19) {
  Database db;
  std::string err;
  ASSERT_EQ(db.load(test::dataPath("dbc/toyota_new_mc_pt_generated.dbc"), err), blvd::core::Status::Ok) << err;
  std::istringstream in(test::comma2k19Candump());
  CandumpReader reader;
  reader.attach(in, "comma2k19");
  Record r;
  std::vector<DecodedSignal> sig;
  std::vector<std::pair<std::string, double>> named;
  size_t frames = 0, signals = 0;
  while (reader.next(r) == CandumpReader::Result::Frame) {
    const Message* m = db.find(r.frame);
    if (!m) continue;
    decode(*m, r.frame, sig);
    if (sig.empty()) continue;
    // Through the physical values only (no raw bits): the general encode path.
    named.clear();
    for (const auto& d : sig) named.emplace_back(d.signal->name, d.value);
    Frame g;
    g.dlc = r.frame.dlc;
    ASSERT_EQ(encode(*m, named, g, err), blvd::core::Status::Ok) << err;
    uint8_t mask[64] = {};
    for (const auto& d : sig) insertRaw(*d.signal, ~0ull, mask);
    for (int i = 0; i < r.frame.dlc; ++i)
      ASSERT_EQ(g.data[i] & mask[i], r.frame.data[i] & mask[i])
          << "line " << r.line << " " << m->name << " byte " << i;
    ++frames;
    signals += sig.size();
  }
  EXPECT_EQ(reader.badLineCount(), 0u);
  EXPECT_GT(frames, 40000u);
  std::printf("encode(decode(frame)) == frame on %zu frames, %zu signals\n", frames, signals);
}

}  // namespace
}  // namespace blvd::can
