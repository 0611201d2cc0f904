// DBC subset: byte-order edge cases (signals crossing bytes, Motorola start
// bits, 64-bit signals, signs) checked against an independent formulation,
// the three shared opendbc files, the multiplexing "unsupported" path, errors
// naming file and line, and encode(decode(frame)) == frame on a real log.
#include <gtest/gtest.h>

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
  EXPECT_EQ(db.parse(text, "bad.dbc", err), want) << text;
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

TEST(Dbc, MultiplexedSignalsAreUnsupportedNotFatal) {
  const Database db = parseDbc(kEdgeDbc);
  const Message& m = *db.findByName("MUXED");
  const Signal* a = m.signal("A");
  ASSERT_NE(a, nullptr);
  EXPECT_FALSE(a->supported);
  EXPECT_EQ(a->multiplex_value, 0);
  EXPECT_EQ(a->unsupported, "unsupported: multiplexed signal A in message MUXED (line 35)");
  EXPECT_TRUE(m.signal("Mode")->supported);
  EXPECT_TRUE(m.signal("Mode")->multiplexor);
  ASSERT_GE(db.diagnostics().size(), 2u);
  EXPECT_EQ(db.diagnostics()[0], "test.dbc:35: unsupported: multiplexed signal A in message MUXED (line 35)");
  // The other signals of the message still decode; the multiplexed ones are left out.
  const Frame f = frameOf(0x103, {0x01, 0x22, 0x33, 0, 0, 0, 0, 0});
  std::vector<DecodedSignal> out;
  ASSERT_EQ(decode(m, f, out), 2u);
  EXPECT_EQ(out[0].signal->name, "Mode");
  EXPECT_EQ(out[0].value, 1);
  EXPECT_EQ(out[1].signal->name, "Plain");
  EXPECT_EQ(out[1].value, 0x33);
  // Encoding one refuses with the same message.
  Frame g;
  std::string err;
  EXPECT_EQ(encode(m, {{"B", 5.0}}, g, err), blvd::core::Status::Unsupported);
  EXPECT_EQ(err, "unsupported: multiplexed signal B in message MUXED (line 36)");
  // And a strict load fails at the first one.
  Database strict;
  DbcOptions opt;
  opt.reject_unsupported = true;
  EXPECT_EQ(strict.parse(kEdgeDbc, "test.dbc", err, opt), blvd::core::Status::Unsupported);
  EXPECT_EQ(err, "test.dbc:35: unsupported: multiplexed signal A in message MUXED (line 35)");
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

TEST(Dbc, ErrorsNameFileAndLine) {
  EXPECT_EQ(parseError("BO_ 1 A: 8 X\n SG_ S : 0|8@2+ (1,0) [0|1] \"\" X\n"),
            "bad.dbc:2: signal S: byte order must be @0 or @1");
  EXPECT_EQ(parseError("\n\n SG_ S : 0|8@1+ (1,0) [0|1] \"\" X\n"), "bad.dbc:3: SG_ outside a BO_ message");
  EXPECT_EQ(parseError("BO_ 1 A: 8 X\n SG_ S : 0|8@1+ (1,0 [0|1] \"\" X\n"),
            "bad.dbc:2: signal S: expected (FACTOR,OFFSET)");
  EXPECT_EQ(parseError("BO_ 1 A: 8 X\n SG_ S : 0|65@1+ (1,0) [0|1] \"\" X\n"),
            "bad.dbc:2: signal S: length 65 is not 1..64 bits");
  EXPECT_EQ(parseError("BO_ 1 A: 8 X\n SG_ S : 500|16@1+ (1,0) [0|1] \"\" X\n"),
            "bad.dbc:2: signal S: bits 500|16 run outside a 64-byte frame");
  EXPECT_EQ(parseError("BO_ 1 A: 8 X\n SG_ S : 0|8@1+ (1,0) [0|1] \"unterminated X\n"),
            "bad.dbc:2: signal S: expected \"UNIT\"");
  EXPECT_EQ(parseError("BO_ 1 A: 8 X\nBO_ 1 B: 8 X\n"), "bad.dbc:2: message B: id 1 already used by A (line 1)");
  EXPECT_EQ(parseError("BO_ 2048 A: 8 X\n"), "bad.dbc:1: message A: id 2048 exceeds 0x7FF (extended ids set bit 31)");
  EXPECT_EQ(parseError("BO_ 1 A: 65 X\n"), "bad.dbc:1: message A: size 65 exceeds 64 bytes");
  EXPECT_EQ(parseError("BO_ 1 A: 8 X\n SG_ S : 0|8@1+ (1,0) [0|1] \"\" X\n SG_ S : 8|8@1+ (1,0) [0|1] \"\" X\n"),
            "bad.dbc:3: signal S declared twice in message A (first at line 2)");
  EXPECT_EQ(parseError("BO_ 1 A: 8 X\n SG_ S x7 : 0|8@1+ (1,0) [0|1] \"\" X\n"),
            "bad.dbc:2: bad multiplexer indicator 'x7' for signal S");
  Database db;
  std::string err;
  EXPECT_EQ(db.load("/nonexistent/x.dbc", err), blvd::core::Status::Io);
  EXPECT_EQ(err.rfind("/nonexistent/x.dbc: cannot open", 0), 0u) << err;
}

TEST(Dbc, LocaleIndependentNumbersAndCrlf) {
  const Database db = parseDbc("BO_ 1 A: 8 X\r\n SG_ S : 0|16@1- (+1E-002,-1.5e1) [-3.2e2|+320] \"\" X\r\n");
  const Signal* s = db.findByName("A")->signal("S");
  ASSERT_NE(s, nullptr);
  EXPECT_DOUBLE_EQ(s->factor, 0.01);
  EXPECT_DOUBLE_EQ(s->offset, -15);
  EXPECT_DOUBLE_EQ(s->minimum, -320);
}

struct SharedDbc {
  const char* file;
  size_t messages;
  size_t signals;
  size_t unsupported;
};

TEST(Dbc, LoadsTheThreeOpendbcFiles) {
  for (const SharedDbc& want : {SharedDbc{"toyota_new_mc_pt_generated.dbc", 55, 330, 0},
                                SharedDbc{"vw_mqb.dbc", 113, 1348, 21},
                                SharedDbc{"hyundai_2015_ccan.dbc", 113, 1154, 6}}) {
    SCOPED_TRACE(want.file);
    Database db;
    std::string err;
    ASSERT_EQ(db.load(test::dataPath(std::string("dbc/") + want.file), err), blvd::core::Status::Ok) << err;
    EXPECT_EQ(db.messages().size(), want.messages);
    size_t signals = 0, unsupported = 0;
    for (const auto& m : db.messages()) {
      signals += m.signals.size();
      for (const auto& s : m.signals) unsupported += !s.supported;
    }
    EXPECT_EQ(signals, want.signals);
    EXPECT_EQ(unsupported, want.unsupported);
  }
  Database vw;
  std::string err;
  ASSERT_EQ(vw.load(test::dataPath("dbc/vw_mqb.dbc"), err), blvd::core::Status::Ok);
  const Signal* ks = vw.findByName("VIN_01")->signal("KS_Geheimnis_1");
  ASSERT_NE(ks, nullptr);
  EXPECT_EQ(ks->unsupported, "unsupported: multiplexed signal KS_Geheimnis_1 in message VIN_01 (line 1243)");
  EXPECT_EQ(vw.diagnostics().front(),
            test::dataPath("dbc/vw_mqb.dbc") +
                ":1243: unsupported: multiplexed signal KS_Geheimnis_1 in message VIN_01 (line 1243)");
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
