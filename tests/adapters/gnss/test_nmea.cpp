// NMEA 0183 parser: framing (partial lines, line ends, garbage, overlong and
// truncated sentences, checksums), every supported sentence type, the epoch
// assembler, and "no allocation per sentence".
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "gnss/nmea.h"

#include "fault/alloc_counter.h"

namespace {

using namespace blvd::gnss;

// Adds "*hh\r\n" to a sentence body like "$GPGGA,...".
std::string withSum(const std::string& body) {
  unsigned sum = 0;
  for (size_t i = 1; i < body.size(); ++i) sum ^= static_cast<unsigned char>(body[i]);
  char tail[8];
  std::snprintf(tail, sizeof tail, "*%02X\r\n", sum);
  return body + tail;
}

std::string readFile(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}
std::string dataPath(const std::string& name) { return std::string(BLVD_TEST_DATA_DIR) + "/nmea/" + name; }

struct Reader final : SentenceReader::Handler {
  std::vector<std::string> sentences;
  std::vector<bool> checksummed;
  std::vector<std::pair<uint64_t, uint64_t>> where;  // line, offset of each sentence
  std::vector<NmeaDiagnostic> diags;
  void onSentence(const Sentence& s) override {
    sentences.emplace_back(s.text);
    checksummed.push_back(s.has_checksum);
    where.emplace_back(s.line, s.offset);
  }
  void onDiagnostic(const NmeaDiagnostic& d) override { diags.push_back(d); }
};

Reader frame(const std::string& bytes, size_t chunk = 0, SentenceReader::Options opt = {}) {
  SentenceReader r(opt);
  Reader out;
  if (chunk == 0) {
    r.feed(bytes.data(), bytes.size(), out);
  } else {
    for (size_t i = 0; i < bytes.size(); i += chunk) r.feed(bytes.data() + i, std::min(chunk, bytes.size() - i), out);
  }
  r.finish(out);
  return out;
}

struct Decoded final : NmeaDecoder::Handler {
  std::vector<Fix> fixes;
  std::vector<NmeaDiagnostic> diags;
  std::vector<std::string> sentences;
  void onFix(const Fix& f) override { fixes.push_back(f); }
  void onDiagnostic(const NmeaDiagnostic& d) override { diags.push_back(d); }
  void onSentence(const Sentence& s, const NmeaRecord*) override { sentences.emplace_back(s.text); }
};

Decoded decode(const std::string& bytes, NmeaDecoder::Options opt = {}) {
  NmeaDecoder d(opt);
  Decoded out;
  d.feed(bytes.data(), bytes.size(), out);
  d.finish(out);
  return out;
}

NmeaRecord record(const std::string& sentence, NmeaDiagnostic* diag = nullptr) {
  const Reader r = frame(sentence);
  EXPECT_EQ(r.sentences.size(), 1u) << sentence;
  // Frame again to get a Sentence that is alive while we decode it.
  struct One final : SentenceReader::Handler {
    NmeaRecord rec;
    bool ok = false;
    NmeaDiagnostic d;
    void onSentence(const Sentence& s) override { ok = decodeSentence(s, &rec, &d); }
    void onDiagnostic(const NmeaDiagnostic&) override {}
  } one;
  SentenceReader sr;
  sr.feed(sentence.data(), sentence.size(), one);
  sr.finish(one);
  if (diag) *diag = one.d;
  return one.ok ? one.rec : NmeaRecord{};
}

const std::string kRmc = withSum("$GPRMC,123519.50,A,4807.038,N,01131.000,W,022.4,084.4,230394,003.1,W,A");
const std::string kGga = withSum("$GPGGA,123519.50,4807.038,N,01131.000,W,1,08,0.9,545.4,M,46.9,M,,");
const std::string kGsa = withSum("$GPGSA,A,3,04,05,,09,12,,,24,,,,,2.5,1.3,2.1");
const std::string kGst = withSum("$GPGST,123519.50,0.006,0.023,0.020,273.6,3.0,4.0,5.5");
const std::string kVtg = withSum("$GPVTG,084.4,T,087.5,M,022.4,N,041.5,K,A");
const std::string kHdt = withSum("$GPHDT,274.07,T");

// ---------------------------------------------------------------------------
// Framing

TEST(NmeaReader, SplitsAtEveryByteBoundaryIdentically) {
  const std::string in = "garbage\r\n" + kRmc + kGga + "$GPGSA,A,1*XX\n" + kGsa;
  const Reader whole = frame(in);
  ASSERT_EQ(whole.sentences.size(), 3u);
  for (size_t chunk = 1; chunk <= in.size(); ++chunk) {
    const Reader r = frame(in, chunk);
    EXPECT_EQ(r.sentences, whole.sentences) << "chunk " << chunk;
    EXPECT_EQ(r.where, whole.where) << "chunk " << chunk;
    ASSERT_EQ(r.diags.size(), whole.diags.size()) << "chunk " << chunk;
    for (size_t i = 0; i < r.diags.size(); ++i) EXPECT_STREQ(r.diags[i].message, whole.diags[i].message);
  }
}

TEST(NmeaReader, AcceptsEveryLineEnding) {
  std::string body = kRmc.substr(0, kRmc.size() - 2);
  for (const char* end : {"\r\n", "\n", "\r", "\r\r\n", "\n\r"}) {
    const Reader r = frame(body + end + body + end);
    EXPECT_EQ(r.sentences.size(), 2u) << "line end " << static_cast<int>(end[0]);
    EXPECT_TRUE(r.diags.empty());
  }
}

TEST(NmeaReader, ReportsGarbageWithLineAndOffsetAndKeepsFollowingData) {
  const std::string in = kRmc + "hello\x01world\r\n" + kGga;
  const Reader r = frame(in);
  ASSERT_EQ(r.sentences.size(), 2u);
  ASSERT_EQ(r.diags.size(), 1u);
  EXPECT_EQ(r.diags[0].code, NmeaError::Garbage);
  EXPECT_EQ(r.diags[0].line, 2u);
  EXPECT_EQ(r.diags[0].offset, kRmc.size());
  EXPECT_NE(std::string(r.diags[0].message).find("line 2, byte " + std::to_string(kRmc.size())), std::string::npos)
      << r.diags[0].message;
  EXPECT_NE(std::string(r.diags[0].message).find("hello\\x01world"), std::string::npos) << r.diags[0].message;
  EXPECT_EQ(r.where[1].first, 3u);
}

TEST(NmeaReader, OverlongSentenceIsRejectedAndResyncs) {
  SentenceReader::Options opt;
  opt.max_sentence = 82;
  const std::string longone = "$GPTXT," + std::string(200, 'x') + "\r\n";
  const Reader r = frame(kRmc + longone + kGga, 0, opt);
  ASSERT_EQ(r.sentences.size(), 2u);
  ASSERT_EQ(r.diags.size(), 1u);
  EXPECT_EQ(r.diags[0].code, NmeaError::Overlong);
  EXPECT_EQ(r.diags[0].line, 2u);
  EXPECT_EQ(r.diags[0].offset, kRmc.size());
  // An overlong run with no line end at all must not swallow the next sentence.
  const Reader r2 = frame("$GPTXT," + std::string(300, 'y') + kGga, 0, opt);
  ASSERT_EQ(r2.sentences.size(), 1u);
  EXPECT_EQ(r2.sentences[0] + "\r\n", kGga);
}

TEST(NmeaReader, BadChecksumNamesLineOffsetAndBothSums) {
  std::string bad = kGga;
  bad[20] = bad[20] == '1' ? '2' : '1';  // change a digit, keep the old checksum
  const Reader r = frame(kRmc + bad + kGsa);
  ASSERT_EQ(r.sentences.size(), 2u);
  ASSERT_EQ(r.diags.size(), 1u);
  const NmeaDiagnostic& d = r.diags[0];
  EXPECT_EQ(d.code, NmeaError::BadChecksum);
  EXPECT_EQ(d.line, 2u);
  EXPECT_EQ(d.offset, kRmc.size());
  EXPECT_STREQ(d.address, "GPGGA");
  const std::string msg = d.message;
  EXPECT_NE(msg.find("bad checksum"), std::string::npos) << msg;
  EXPECT_NE(msg.find("says *"), std::string::npos) << msg;
}

TEST(NmeaReader, MalformedChecksums) {
  for (const char* tail : {"*", "*1", "*1G", "*123"}) {
    const Reader r = frame(std::string("$GPGSA,A,1") + tail + "\r\n" + kGsa);
    ASSERT_EQ(r.sentences.size(), 1u) << tail;
    ASSERT_EQ(r.diags.size(), 1u) << tail;
    EXPECT_EQ(r.diags[0].code, NmeaError::MalformedChecksum) << tail;
  }
  // Lower-case hex digits are fine.
  std::string lower = kGsa;
  for (char& c : lower)
    if (c >= 'A' && c <= 'F' && &c > &lower[lower.find('*')]) c = static_cast<char>(c - 'A' + 'a');
  EXPECT_TRUE(frame(lower).diags.empty());
}

TEST(NmeaReader, SentenceWithoutChecksumIsAcceptedAndMarked) {
  const std::string plain = "$GPGLL,4916.45,N,12311.12,W,225444,A\r\n";
  const Reader r = frame(plain + kGsa);
  ASSERT_EQ(r.sentences.size(), 2u);
  EXPECT_TRUE(r.diags.empty());
  EXPECT_FALSE(r.checksummed[0]);
  EXPECT_TRUE(r.checksummed[1]);
  // ... and a fix built from it says so.
  const Decoded d = decode(withSum("$GPRMC,225444,A,4916.45,N,12311.12,W,0.5,54.7,191194,,") + plain);
  ASSERT_EQ(d.fixes.size(), 1u);
  EXPECT_TRUE(d.fixes[0].flags & kFixNoChecksum);
  // With require_checksum it is an error instead.
  SentenceReader::Options strict;
  strict.require_checksum = true;
  const Reader s = frame(plain + kGsa, 0, strict);
  ASSERT_EQ(s.sentences.size(), 1u);
  ASSERT_EQ(s.diags.size(), 1u);
  EXPECT_EQ(s.diags[0].code, NmeaError::MissingChecksum);
}

TEST(NmeaReader, NewSentenceInsideAnotherTruncatesIt) {
  // The first is cut off mid-field: reported; the second is intact.
  const Reader r = frame("$GPGGA,1235" + kRmc);
  ASSERT_EQ(r.sentences.size(), 1u);
  ASSERT_EQ(r.diags.size(), 1u);
  EXPECT_EQ(r.diags[0].code, NmeaError::Truncated);
  EXPECT_EQ(r.diags[0].offset, 0u);
  // A sentence complete up to its checksum only lost its CR LF: kept.
  const std::string gsa = kGsa.substr(0, kGsa.size() - 2);
  const Reader r2 = frame(gsa + kRmc);
  EXPECT_EQ(r2.sentences.size(), 2u);
  EXPECT_TRUE(r2.diags.empty());
}

TEST(NmeaReader, ControlByteInsideSentenceDropsIt) {
  const Reader r = frame(std::string("$GPRMC,0003\0\0\0   \r\n", 19) + kGga);
  ASSERT_EQ(r.sentences.size(), 1u);
  ASSERT_EQ(r.diags.size(), 1u);
  EXPECT_EQ(r.diags[0].code, NmeaError::BadByte);
  EXPECT_NE(std::string(r.diags[0].message).find("0x00"), std::string::npos);
}

TEST(NmeaReader, EndOfInput) {
  // Cut off at the end: reported as truncated.
  Reader r = frame(kRmc + "$GPGGA,012530.562,4131.7353,N,09336.8150,W,0,00,50.");
  ASSERT_EQ(r.diags.size(), 1u);
  EXPECT_EQ(r.diags[0].code, NmeaError::Truncated);
  EXPECT_EQ(r.diags[0].line, 2u);
  // Complete with its checksum, only the line end missing: accepted.
  r = frame(kRmc + kGsa.substr(0, kGsa.size() - 2));
  EXPECT_EQ(r.sentences.size(), 2u);
  EXPECT_TRUE(r.diags.empty());
}

TEST(NmeaReader, HashCommentLinesAreSkipped) {
  const Reader r = frame("# Name: test\r\n#\n" + kRmc + "#not a comment here? yes, at line start\n" + kGga);
  EXPECT_EQ(r.sentences.size(), 2u);
  EXPECT_TRUE(r.diags.empty());
  EXPECT_EQ(r.where[0].first, 3u);
  // Not at line start: garbage.
  const Reader g = frame(kRmc + "  # trailing\r\n");
  EXPECT_EQ(g.diags.size(), 1u);
}

TEST(NmeaReader, BadAddress) {
  const Reader r = frame("$gpgga,1*00\r\n$G\r\n" + kRmc);
  EXPECT_EQ(r.sentences.size(), 1u);
  ASSERT_EQ(r.diags.size(), 2u);
  EXPECT_EQ(r.diags[0].code, NmeaError::BadAddress);
  EXPECT_EQ(r.diags[1].code, NmeaError::BadAddress);
}

// Every bad checksum in the shared logs is reported, at its line and offset,
// and nothing else is called a bad checksum. The expected set is computed
// here independently: each '$'-started piece of a line that ends in *hh.
TEST(NmeaReader, EveryBadChecksumInTheSharedLogs) {
  int total = 0;
  for (const char* log : {"beidou-bd.log", "bt451.log", "bu353-glonass.log", "firefly-II.log", "garmin-geko201.log",
                          "gp-320fw-2019-04-07-coldboot.log", "haicom-305N.log", "holux-gm-210.log",
                          "nmea-fuzzy-cases.log", "nmea-rtk.log", "quectel-eg25-g.log", "skytraq-PX1172RH_DS.log",
                          "telit-pls83-w.log", "ublox-zed-f9p-nmea.log"}) {
    const std::string bytes = readFile(dataPath(log));
    ASSERT_FALSE(bytes.empty()) << log;
    std::set<std::pair<uint64_t, uint64_t>> expected;
    uint64_t line = 1;
    size_t line_start = 0;
    while (line_start < bytes.size()) {
      size_t end = bytes.find('\n', line_start);
      if (end == std::string::npos) end = bytes.size();
      std::string text = bytes.substr(line_start, end - line_start);
      // Pieces starting at each '$'.
      for (size_t p = text.find('$'); p != std::string::npos;) {
        const size_t next = text.find('$', p + 1);
        std::string piece = text.substr(p, next == std::string::npos ? std::string::npos : next - p);
        piece = piece.substr(0, piece.find('\r'));  // a lone CR ends a sentence too
        bool printable = true;
        for (const char c : piece) printable = printable && c >= 0x20 && c < 0x7f;
        const size_t star = piece.rfind('*');
        const std::string address = piece.substr(1, piece.find_first_of(",*") - 1);
        bool address_ok = address.size() >= 3 && address.size() <= 8;
        for (const char c : address) address_ok = address_ok && (std::isupper(c) || std::isdigit(c));
        if (text[0] != '#' && printable && address_ok && star != std::string::npos && piece.size() == star + 3 &&
            std::isxdigit(piece[star + 1]) && std::isxdigit(piece[star + 2])) {
          unsigned sum = 0;
          for (size_t i = 1; i < star; ++i) sum ^= static_cast<unsigned char>(piece[i]);
          if (sum != std::stoul(piece.substr(star + 1), nullptr, 16)) expected.emplace(line, line_start + p);
        }
        p = next;
      }
      ++line;
      line_start = end + 1;
    }
    const Reader r = frame(bytes);
    std::set<std::pair<uint64_t, uint64_t>> got;
    for (const auto& d : r.diags)
      if (d.code == NmeaError::BadChecksum) got.emplace(d.line, d.offset);
    EXPECT_EQ(got, expected) << log;
    total += static_cast<int>(got.size());
    // firefly-II: its 23 GGA sentences have wrong checksums; gpsd dropped them too.
    if (std::string(log) == "firefly-II.log") {
      EXPECT_EQ(got.size(), 23u);
    }
  }
  EXPECT_GT(total, 40);
}

// Every sentence gpsd accepted (echoed in the .chk) we accept too, in order.
TEST(NmeaReader, AcceptsEverySentenceGpsdAccepted) {
  for (const char* log : {"beidou-bd.log", "bt451.log", "bu353-glonass.log", "firefly-II.log", "garmin-geko201.log",
                          "gp-320fw-2019-04-07-coldboot.log", "haicom-305N.log", "holux-gm-210.log",
                          "nmea-fuzzy-cases.log", "nmea-rtk.log", "quectel-eg25-g.log", "skytraq-PX1172RH_DS.log",
                          "telit-pls83-w.log", "ublox-zed-f9p-nmea.log"}) {
    const Reader ours = frame(readFile(dataPath(log)));
    std::ifstream chk(dataPath(std::string(log) + ".chk"), std::ios::binary);
    std::string line;
    size_t at = 0, echoed = 0;
    while (std::getline(chk, line)) {
      while (!line.empty() && (line.back() == '\r' || line.back() == '\n')) line.pop_back();
      if (line.empty() || line[0] != '$') continue;
      ++echoed;
      while (at < ours.sentences.size() && ours.sentences[at] != line) ++at;
      ASSERT_LT(at, ours.sentences.size()) << log << ": gpsd accepted, we did not: " << line;
      ++at;
    }
    EXPECT_GT(echoed, 0u) << log;
  }
}

// ---------------------------------------------------------------------------
// Decoding

TEST(NmeaDecode, Rmc) {
  const NmeaRecord r = record(kRmc);
  EXPECT_EQ(r.type, SentenceType::RMC);
  EXPECT_STREQ(r.talker, "GP");
  ASSERT_TRUE(r.has_tod);
  EXPECT_EQ(r.tod_ms, (12 * 3600 + 35 * 60 + 19) * 1000 + 500);
  EXPECT_EQ(r.status, 'A');
  ASSERT_TRUE(r.has_pos);
  EXPECT_NEAR(r.lat, 48 + 7.038 / 60, 1e-12);
  EXPECT_NEAR(r.lon, -(11 + 31.0 / 60), 1e-12);
  EXPECT_NEAR(r.speed_mps, 22.4 * 1852 / 3600, 1e-9);
  EXPECT_NEAR(r.track_deg, 84.4, 1e-12);
  ASSERT_TRUE(r.has_date);
  EXPECT_EQ(r.year, 1994);
  EXPECT_EQ(r.month, 3);
  EXPECT_EQ(r.day, 23);
  EXPECT_EQ(r.faa, 'A');
  // Two-digit years: 80..99 -> 19xx, 00..79 -> 20xx.
  EXPECT_EQ(record(withSum("$GNRMC,000000,V,,,,,,,010179,,,N")).year, 2079);
  EXPECT_EQ(record(withSum("$GNRMC,000000,V,,,,,,,010180,,,N")).year, 1980);
  // Quectel with nothing at all.
  const NmeaRecord q = record("$GPRMC,,V,,,,,,,,,,N*53\r\n");
  EXPECT_EQ(q.type, SentenceType::RMC);
  EXPECT_FALSE(q.has_tod);
  EXPECT_FALSE(q.has_pos);
  EXPECT_TRUE(std::isnan(q.speed_mps));
}

TEST(NmeaDecode, Gga) {
  const NmeaRecord r = record(kGga);
  EXPECT_EQ(r.type, SentenceType::GGA);
  EXPECT_EQ(r.quality, 1);
  EXPECT_EQ(r.sats, 8);
  EXPECT_DOUBLE_EQ(r.hdop, 0.9);
  EXPECT_DOUBLE_EQ(r.alt, 545.4);
  EXPECT_DOUBLE_EQ(r.geoid_sep, 46.9);
  // Seven decimals of minutes (survey receivers) survive to 1e-9 degrees.
  const NmeaRecord p = record(withSum("$GNGGA,132819.60,4134.49795459,N,09345.03431408,W,2,10,0.9,278.161,M,-31.442,M,6.6,0133"));
  EXPECT_NEAR(p.lat, 41.574965910, 5e-10);
  EXPECT_NEAR(p.lon, -93.750571901, 5e-10);
  EXPECT_DOUBLE_EQ(p.geoid_sep, -31.442);
}

TEST(NmeaDecode, Gns) {
  const NmeaRecord r = record(withSum("$GNGNS,043539.00,4333.190206,N,00127.618380,E,AAAAN,14,1.3,250.8,50.0,,,V"));
  EXPECT_EQ(r.type, SentenceType::GNS);
  EXPECT_EQ(r.faa, 'A');
  EXPECT_EQ(r.sats, 14);
  EXPECT_DOUBLE_EQ(r.alt, 250.8);
  EXPECT_EQ(r.nav_status, 'V');
  EXPECT_NEAR(r.lat, 43 + 33.190206 / 60, 1e-12);
}

TEST(NmeaDecode, Vtg) {
  NmeaRecord r = record(kVtg);
  EXPECT_EQ(r.type, SentenceType::VTG);
  EXPECT_DOUBLE_EQ(r.track_deg, 84.4);
  EXPECT_NEAR(r.speed_mps, 22.4 * 1852 / 3600, 1e-9);
  // km/h when knots are missing; the pre-NMEA-2.0 form without unit letters.
  r = record(withSum("$GPVTG,10.0,T,,M,,N,36.0,K,A"));
  EXPECT_NEAR(r.speed_mps, 10.0, 1e-9);
  r = record(withSum("$GPVTG,054.7,034.4,005.5,010.2"));
  EXPECT_DOUBLE_EQ(r.track_deg, 54.7);
  EXPECT_NEAR(r.speed_mps, 5.5 * 1852 / 3600, 1e-9);
}

TEST(NmeaDecode, Gsa) {
  NmeaRecord r = record(kGsa);
  EXPECT_EQ(r.type, SentenceType::GSA);
  EXPECT_EQ(r.gsa_mode, 3);
  EXPECT_DOUBLE_EQ(r.pdop, 2.5);
  EXPECT_DOUBLE_EQ(r.hdop, 1.3);
  EXPECT_DOUBLE_EQ(r.vdop, 2.1);
  // NMEA 4.1 system id after the DOPs.
  r = record("$GNGSA,A,3,13,16,21,15,10,29,27,20,,,,,1.05,0.64,0.83,1*03\r\n");
  EXPECT_EQ(r.gsa_mode, 3);
  EXPECT_DOUBLE_EQ(r.vdop, 0.83);
  EXPECT_EQ(record("$GPGSA,A,1,,,,,,,,,,,,,,,*1E\r\n").gsa_mode, 1);
}

TEST(NmeaDecode, Gst) {
  const NmeaRecord r = record(kGst);
  EXPECT_EQ(r.type, SentenceType::GST);
  EXPECT_TRUE(r.has_tod);
  EXPECT_DOUBLE_EQ(r.lat_err, 3.0);
  EXPECT_DOUBLE_EQ(r.lon_err, 4.0);
  EXPECT_DOUBLE_EQ(r.alt_err, 5.5);
}

TEST(NmeaDecode, Gll) {
  NmeaRecord r = record("$GPGLL,4808.9993,N,01135.0798,E,000343.03,A,A*60\r\n");
  EXPECT_EQ(r.type, SentenceType::GLL);
  EXPECT_TRUE(r.has_pos);
  EXPECT_EQ(r.tod_ms, 223030);
  EXPECT_EQ(r.status, 'A');
  // NMEA 1.x form: position only.
  r = record(withSum("$GPGLL,4916.45,N,12311.12,W"));
  EXPECT_TRUE(r.has_pos);
  EXPECT_FALSE(r.has_tod);
}

TEST(NmeaDecode, Zda) {
  const NmeaRecord r = record("$GPZDA,152504.50,09,12,2009,00,00*65\r\n");
  EXPECT_EQ(r.type, SentenceType::ZDA);
  EXPECT_TRUE(r.has_date);
  EXPECT_EQ(r.year, 2009);
  EXPECT_EQ(r.month, 12);
  EXPECT_EQ(r.day, 9);
  EXPECT_EQ(r.tod_ms, (15 * 3600 + 25 * 60 + 4) * 1000 + 500);
}

TEST(NmeaDecode, HdtAndThs) {
  EXPECT_DOUBLE_EQ(record(kHdt).heading_deg, 274.07);
  const NmeaRecord t = record("$GNTHS,244.28,A*11\r\n");
  EXPECT_EQ(t.type, SentenceType::THS);
  EXPECT_DOUBLE_EQ(t.heading_deg, 244.28);
  EXPECT_EQ(t.faa, 'A');
}

TEST(NmeaDecode, TalkersAndSkippedSentences) {
  for (const char* talker : {"GP", "GN", "GL", "GA", "GB", "BD", "GQ"}) {
    const NmeaRecord r = record(withSum(std::string("$") + talker + "GSA,A,3,01,02,03,04,,,,,,,,,2.0,1.0,1.5"));
    EXPECT_EQ(r.type, SentenceType::GSA) << talker;
    EXPECT_EQ(r.talker[0], talker[0]);
    EXPECT_EQ(r.talker[1], talker[1]);
  }
  // Proprietary, unknown sentence types and non-GNSS talkers: skipped, no error.
  for (const std::string& s : {withSum("$PGRME,15.0,M,22.5,M,27.0,M"), withSum("$GPGSV,1,1,01,05,40,083,46"),
                              withSum("$IIHDT,274.07,T"), withSum("$GPXYZ,1,2")}) {
    NmeaDiagnostic d;
    const NmeaRecord r = record(s, &d);
    EXPECT_EQ(r.type, SentenceType::Unknown) << s;
    EXPECT_EQ(d.code, NmeaError::None) << s;
  }
}

TEST(NmeaDecode, MalformedFieldRejectsTheSentenceWithAClearReason) {
  struct Case {
    std::string sentence;
    const char* says;
  };
  const Case cases[] = {
      {withSum("$GPGGA,123519,48x7.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,"), "field 2 (latitude)"},
      {withSum("$GPGGA,123519,4807.038,Q,01131.000,E,1,08,0.9,545.4,M,46.9,M,,"), "field 3 (N/S)"},
      {withSum("$GPGGA,1235,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,"), "field 1 (time)"},
      {withSum("$GPGGA,126519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,"), "field 1 (time)"},
      {withSum("$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,abc,M,46.9,M,,"), "field 9 (altitude)"},
      {withSum("$GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,231394,003.1,W"), "field 9 (date)"},
      {withSum("$GPRMC,123519,X,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W"), "field 2 (status)"},
      {withSum("$GPRMC,123519,A,4867.038,N,01131.000,E,022.4,084.4,230394,003.1,W"), "field 3 (latitude)"},
      {withSum("$GPGSA,A,4,,,,,,,,,,,,,1,1,1"), "field 2 (fix type)"},
      {withSum("$GPZDA,123519,32,03,2004,,"), "field 2 (day)"},
      {withSum("$GPGGA,123519,4807.038,N"), "too few fields"},
  };
  for (const Case& c : cases) {
    const std::string in = c.sentence + kRmc;
    const Decoded d = decode(in);
    ASSERT_EQ(d.diags.size(), 1u) << c.sentence;
    const std::string msg = d.diags[0].message;
    EXPECT_NE(msg.find("line 1, byte 0"), std::string::npos) << msg;
    EXPECT_NE(msg.find(c.says), std::string::npos) << msg;
    // The good RMC after it still makes its fix, with nothing from the bad one.
    ASSERT_EQ(d.fixes.size(), 1u) << c.sentence;
    EXPECT_NEAR(d.fixes[0].lon, -(11 + 31.0 / 60), 1e-9) << c.sentence;
  }
}

// ---------------------------------------------------------------------------
// Epochs

TEST(NmeaEpoch, MergesOneCycleIntoOneFix) {
  const Decoded d = decode(kRmc + kVtg + kGga + kGsa + kGst + kHdt);
  ASSERT_EQ(d.fixes.size(), 1u);
  const Fix& f = d.fixes[0];
  EXPECT_EQ(f.mode, kMode3D);
  EXPECT_EQ(f.status, kStatusGps);
  char t[40];
  formatIso8601(f.t_unix, t, sizeof t);
  EXPECT_STREQ(t, "1994-03-23T12:35:19.500Z");
  EXPECT_NEAR(f.lat, 48 + 7.038 / 60, 1e-12);
  EXPECT_DOUBLE_EQ(f.alt, 545.4);
  EXPECT_NEAR(f.speed_mps, 22.4 * 1852 / 3600, 1e-5);
  EXPECT_NEAR(f.track_deg, 84.4, 1e-5);
  EXPECT_NEAR(f.hdop, 1.3, 1e-6);  // the GSA came after the GGA
  EXPECT_NEAR(f.pdop, 2.5, 1e-6);
  EXPECT_NEAR(f.lat_err_m, 3.0, 1e-6);
  EXPECT_NEAR(f.h_acc_m, 5.0, 1e-6);
  EXPECT_NEAR(f.v_acc_m, 5.5, 1e-6);
  EXPECT_NEAR(f.heading_deg, 274.07, 1e-4);
  EXPECT_NEAR(f.geoid_sep_m, 46.9, 1e-5);
  EXPECT_EQ(f.sats_used, 8);
  const uint32_t all = kFixHasTime | kFixHasLatLon | kFixHasAlt | kFixHasSpeed | kFixHasTrack | kFixHasHdop |
                       kFixHasHAcc | kFixHasVAcc | kFixHasHeading | kFixHasGeoidSep | kFixHasPdop;
  EXPECT_EQ(f.flags, all);
  char json[256];
  formatTpvJson(f, json, sizeof json);
  EXPECT_STREQ(json,
               "{\"class\":\"TPV\",\"mode\":3,\"time\":\"1994-03-23T12:35:19.500Z\",\"lat\":48.117300000,"
               "\"lon\":-11.516666667,\"alt\":545.4000,\"speed\":11.524,\"track\":84.4000}");
}

TEST(NmeaEpoch, DateCarriesOverAndRollsAtMidnight) {
  const std::string in = withSum("$GPRMC,235959.00,A,4807.038,N,01131.000,E,0.0,0.0,311299,,") +
                         withSum("$GPGGA,235959.50,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,") +
                         withSum("$GPGGA,000000.00,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,");
  const Decoded d = decode(in);
  ASSERT_EQ(d.fixes.size(), 3u);
  char t[40];
  formatIso8601(d.fixes[1].t_unix, t, sizeof t);
  EXPECT_STREQ(t, "1999-12-31T23:59:59.500Z");
  formatIso8601(d.fixes[2].t_unix, t, sizeof t);
  EXPECT_STREQ(t, "2000-01-01T00:00:00.000Z");
  // Without any RMC (status A) or ZDA there is no date, so no time.
  const Decoded nodate = decode(withSum("$GPGGA,000000.00,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,"));
  ASSERT_EQ(nodate.fixes.size(), 1u);
  EXPECT_FALSE(nodate.fixes[0].flags & kFixHasTime);
  EXPECT_TRUE(std::isnan(nodate.fixes[0].t_unix));
  EXPECT_EQ(nodate.fixes[0].mode, kMode3D);
}

TEST(NmeaEpoch, ModeRules) {
  auto mode = [](const std::string& in) {
    const Decoded d = decode(in);
    return d.fixes.empty() ? -1 : d.fixes.back().mode;
  };
  const std::string rmc_a = withSum("$GPRMC,120000,A,4807.038,N,01131.000,E,0.0,0.0,010120,,");
  const std::string rmc_v = withSum("$GPRMC,120000,V,4807.038,N,01131.000,E,0.0,0.0,010120,,");
  const std::string gga3 = withSum("$GPGGA,120000,4807.038,N,01131.000,E,1,05,0.9,545.4,M,46.9,M,,");
  const std::string gga_2sats = withSum("$GPGGA,120000,4807.038,N,01131.000,E,1,03,0.9,545.4,M,46.9,M,,");
  const std::string gga0 = withSum("$GPGGA,120000,4807.038,N,01131.000,E,0,00,,,M,,M,,");
  const std::string gsa2 = withSum("$GPGSA,A,2,01,02,03,,,,,,,,,,2.0,1.0,1.7");
  const std::string gsa3 = withSum("$GPGSA,A,3,01,02,03,04,,,,,,,,,2.0,1.0,1.7");
  EXPECT_EQ(mode(rmc_a), kMode2D);                // RMC only: 2D
  EXPECT_EQ(mode(rmc_v), kModeNoFix);
  EXPECT_EQ(mode(rmc_a + gga3), kMode3D);         // altitude from 5 satellites
  EXPECT_EQ(mode(rmc_a + gga_2sats), kMode2D);
  EXPECT_EQ(mode(rmc_a + gga_2sats + gsa3), kMode3D);  // the receiver says so
  EXPECT_EQ(mode(rmc_a + gga_2sats + gsa2), kMode2D);
  EXPECT_EQ(mode(rmc_a + gga3 + gsa2), kMode3D);  // gpsd: a 2D GSA does not downgrade that
  EXPECT_EQ(mode(rmc_a + gga0), kModeNoFix);      // any "no fix" wins
  EXPECT_EQ(mode(rmc_v + gga3 + gsa3), kModeNoFix);
  // GSA arriving at a lower rate: the last one (<= 10 s) still counts.
  const std::string next = withSum("$GPGGA,120001,4807.038,N,01131.000,E,1,03,0.9,545.4,M,46.9,M,,");
  EXPECT_EQ(mode(rmc_a + gga_2sats + gsa3 + next), kMode3D);
  const std::string later = withSum("$GPGGA,120030,4807.038,N,01131.000,E,1,03,0.9,545.4,M,46.9,M,,");
  EXPECT_EQ(mode(rmc_a + gga_2sats + gsa3 + later), kMode2D);
}

// gpsd's mode across epochs (drivers/driver_nmea0183.c: the last sentence of a
// cycle that states a mode wins; RMC takes 3D from the last GSA's satellites).
// Each epoch ends with a ZDA; `modes` gives one mode per epoch, in order.
TEST(NmeaEpoch, ModeAsGpsdDecidesIt) {
  const auto rmc = [](const char* t, const char* faa = "A") {
    return withSum(std::string("$GPRMC,") + t + ",A,4807.038,N,01131.000,E,0.0,0.0,010124,,," + faa);
  };
  const auto gga = [](const char* t, int q, const char* sats, const char* alt) {
    return withSum(std::string("$GPGGA,") + t + ",4807.038,N,01131.000,E," + std::to_string(q) + "," + sats + ",0.9," +
                   alt + ",M,46.9,M,,");
  };
  const auto zda = [](const char* t) { return withSum(std::string("$GPZDA,") + t + ",01,01,2024,00,00"); };
  const auto gll = [](const char* t) { return withSum(std::string("$GPGLL,4807.038,N,01131.000,E,") + t + ",A,A"); };
  const std::string gsa3 = withSum("$GPGSA,A,3,01,02,03,04,05,06,07,08,,,,,1.5,0.9,1.2");
  const std::string gsa2 = withSum("$GPGSA,A,2,01,02,03,,,,,,,,,,2.5,2.3,1.0");
  const std::string gsa1 = withSum("$GPGSA,A,1,,,,,,,,,,,,,,,");
  const char* t[] = {"120000.00", "120001.00", "120002.00"};
  const auto modes = [](const std::string& in) {
    std::vector<int> m;
    for (const Fix& f : decode(in).fixes) {
      if (f.flags & kFixUpdate) m.back() = f.mode;
      else m.push_back(f.mode);
    }
    return m;
  };
  const auto full3d = [&](int i) { return rmc(t[i]) + gga(t[i], 1, "08", "545.4") + gsa3 + zda(t[i]); };
  // A GSA of fix type 1 as the epoch's last word on the mode: no fix (gpsd 3, 1, 3).
  EXPECT_EQ(modes(full3d(0) + rmc(t[1]) + gga(t[1], 1, "08", "545.4") + gsa1 + zda(t[1]) + full3d(2)),
            (std::vector<int>{kMode3D, kModeNoFix, kMode3D}));
  // ...unless a position sentence follows it (gpsd 3: u-blox sends GLL last).
  EXPECT_EQ(modes(rmc(t[0]) + gga(t[0], 1, "08", "545.4") + gsa1 + gll(t[0])), (std::vector<int>{kMode3D}));
  // RMC-only epochs between GSAs: the last GSA's 3D holds (gpsd 3, 3, 3).
  const auto rmc_gsa = [&](int i) { return rmc(t[i]) + gsa3 + zda(t[i]); };
  EXPECT_EQ(modes(rmc_gsa(0) + rmc(t[1]) + zda(t[1]) + rmc_gsa(2)),
            (std::vector<int>{kMode3D, kMode3D, kMode3D}));
  // Dead reckoning from no satellites: GGA quality 6 with 00 used is no fix (gpsd 3, 1).
  EXPECT_EQ(modes(full3d(0) + rmc(t[1], "E") + gga(t[1], 6, "00", "545.4") + zda(t[1])),
            (std::vector<int>{kMode3D, kModeNoFix}));
  // Where gpsd looks at the previous cycle and we do not (nmea.h, "mode"):
  // a 2D receiver holding an altitude from 3 satellites (gpsd 2, 3, 3),
  const auto held = [&](int i) { return rmc(t[i]) + gga(t[i], 1, "03", "50.0") + gsa2 + zda(t[i]); };
  EXPECT_EQ(modes(held(0) + held(1) + held(2)), (std::vector<int>{kMode2D, kMode2D, kMode2D}));
  // and the altitude going away (gpsd 3, 3, 2).
  const auto lost = [&](int i) { return rmc(t[i]) + gga(t[i], 1, "03", "") + gsa2 + zda(t[i]); };
  EXPECT_EQ(modes(full3d(0) + lost(1) + lost(2)), (std::vector<int>{kMode3D, kMode2D, kMode2D}));
}

TEST(NmeaEpoch, GstBeforeItsGgaStillApplies) {
  const Decoded d = decode(kGst + kRmc + kGga);
  ASSERT_EQ(d.fixes.size(), 1u);
  EXPECT_TRUE(d.fixes[0].flags & kFixHasHAcc);
  // A GST of another time does not.
  const Decoded e = decode(withSum("$GPGST,123518.50,0.006,0.023,0.020,273.6,3.0,4.0,5.5") + kRmc + kGga);
  ASSERT_EQ(e.fixes.size(), 1u);
  EXPECT_FALSE(e.fixes[0].flags & kFixHasHAcc);
}

// Once the cycle is learned, a fix comes out right after the cycle's last
// sentence, not one cycle later when the next one starts.
TEST(NmeaEpoch, EarlyEmissionAfterLearningTheCycle) {
  auto cycle = [](int sec) {
    char t[24];  // room for any int (GCC checks the bound under the sanitizers)
    std::snprintf(t, sizeof t, "1200%02d.00", sec);
    return withSum(std::string("$GPRMC,") + t + ",A,4807.038,N,01131.000,E,1.0,10.0,010120,,") +
           withSum(std::string("$GPGGA,") + t + ",4807.038,N,01131.000,E,1,05,0.9,545.4,M,46.9,M,,") + kGsa;
  };
  NmeaDecoder dec;
  Decoded out;
  for (int s = 0; s < 3; ++s) {
    const std::string c = cycle(s);
    dec.feed(c.data(), c.size(), out);
  }
  // Cycles 0 and 1 closed when the next began; cycle 2 ended with the learned
  // ender (GPGSA) and was emitted without waiting.
  ASSERT_EQ(out.fixes.size(), 3u);
  EXPECT_EQ(out.fixes[2].flags & kFixUpdate, 0u);
  // A late sentence of the same epoch: the fix is emitted again, marked.
  const std::string hdt = kHdt;
  dec.feed(hdt.data(), hdt.size(), out);
  const std::string c3 = cycle(3);
  dec.feed(c3.data(), c3.size(), out);
  ASSERT_GE(out.fixes.size(), 4u);
  EXPECT_TRUE(out.fixes[3].flags & kFixUpdate);
  EXPECT_TRUE(out.fixes[3].flags & kFixHasHeading);
  EXPECT_EQ(out.fixes[3].t_unix, out.fixes[2].t_unix);
  // Without early emission the same input gives no update.
  NmeaDecoder::Options late;
  late.assembler.early_emit = false;
  std::string all;
  for (int s = 0; s < 3; ++s) all += cycle(s);
  all += kHdt + c3;
  const Decoded l = decode(all, late);
  EXPECT_EQ(l.fixes.size(), 4u);
  for (const Fix& f : l.fixes) EXPECT_EQ(f.flags & kFixUpdate, 0u);
}

// Receivers do not send every sentence of their cycle every time: no GST (or
// an empty one) without a fix, GSA every few cycles. Once the cycle is learned,
// an epoch that lacks its last sentences must not teach the assembler a
// shorter cycle: the next complete epoch would be emitted at that earlier
// sentence and again, as an update, when its GST (or GSA) arrives - one epoch,
// two fixes for a consumer such as the replayer, which feeds both.
TEST(NmeaEpoch, EachEpochOnceWhateverSubsetOfTheCycleArrives) {
  auto time = [](int sec) {
    char t[24];
    std::snprintf(t, sizeof t, "12%02d%02d.00", sec / 60 % 60, sec % 60);
    return std::string(t);
  };
  auto rmc = [&](int sec, bool fix) {
    return withSum("$GPRMC," + time(sec) + (fix ? ",A,4807.038,N,01131.000,E,1.0,10.0,010120,,,A" : ",V,,,,,,,010120,,,N"));
  };
  auto gga = [&](int sec, bool fix) {
    return withSum("$GPGGA," + time(sec) + (fix ? ",4807.038,N,01131.000,E,1,05,0.9,545.4,M,46.9,M,," : ",,,,,0,00,,,M,,M,,"));
  };
  auto gsa = [](bool fix) { return withSum(fix ? "$GPGSA,A,3,01,02,03,04,,,,,,,,,2.0,1.0,1.7" : "$GPGSA,A,1,,,,,,,,,,,,,,,"); };
  auto gst = [&](int sec) { return withSum("$GPGST," + time(sec) + ",1.0,1.0,1.0,0.0,3.0,4.0,5.5"); };
  // Each cycle as a list of sentences; after every cycle, the fixes so far.
  auto run = [](const std::vector<std::vector<std::string>>& cycles, std::vector<size_t>* after) {
    NmeaDecoder dec;
    Decoded out;
    for (const auto& c : cycles) {
      for (const std::string& s : c) dec.feed(s.data(), s.size(), out);
      after->push_back(out.fixes.size());
    }
    dec.finish(out);
    return out;
  };
  // One fix per epoch, in time order; updates only at the fix indices in `updates`.
  auto expectOncePerEpoch = [](const Decoded& d, size_t epochs, const std::set<size_t>& updates, const char* what) {
    ASSERT_EQ(d.fixes.size(), epochs + updates.size()) << what;
    size_t epoch = 0;
    for (size_t i = 0; i < d.fixes.size(); ++i) {
      const Fix& f = d.fixes[i];
      const bool update = (f.flags & kFixUpdate) != 0;
      EXPECT_EQ(update, updates.count(i) == 1) << what << ": fix " << i << ", t " << std::fixed << f.t_unix;
      if (i > 0 && !update) {
        EXPECT_GT(f.t_unix, d.fixes[i - 1].t_unix) << what << ": fix " << i;
      }
      epoch += update ? 0 : 1;
    }
    EXPECT_EQ(epoch, epochs) << what;
  };

  // 1. An outage: 5 cycles of RMC V, GGA 0, GSA 1 without GST between full ones.
  std::vector<std::vector<std::string>> outage;
  for (int s = 0; s < 15; ++s) {
    const bool fix = s < 5 || s >= 10;
    if (fix)
      outage.push_back({rmc(s, true), gga(s, true), gsa(true), gst(s)});
    else
      outage.push_back({rmc(s, false), gga(s, false), gsa(false)});
  }
  std::vector<size_t> after;
  const Decoded a = run(outage, &after);
  expectOncePerEpoch(a, 15, {}, "outage without GST");
  if (a.fixes.size() == 15) {
    EXPECT_EQ(a.fixes[10].mode, kMode3D);
    EXPECT_TRUE(a.fixes[10].flags & kFixHasHAcc);  // the first fix after the outage has its GST
    EXPECT_EQ(a.fixes[7].mode, kModeNoFix);
  }
  // Early emission still works: once learned, a full cycle is out at its GST.
  EXPECT_EQ(after[3], 4u);
  EXPECT_EQ(after[12], 13u);
  // The outage epochs (no GST: the learned ender is missing) close when the next begins.
  EXPECT_EQ(after[6], 6u);

  // 2. GSA every 5th cycle only, after GGA. Its first one follows the ender
  // learned from RMC + GGA cycles: a sentence never seen in the cycle before,
  // so that epoch (fix 4) is completed by an update, inherently (the assembler
  // cannot know of a sentence before it has seen it). The later ones do not
  // shorten the cycle again: no update at cycles 9, 14, 19.
  std::vector<std::vector<std::string>> sparse_gsa;
  for (int s = 0; s < 20; ++s) {
    sparse_gsa.push_back({rmc(s, true), gga(s, true)});
    if (s % 5 == 4) sparse_gsa.back().push_back(gsa(true));
  }
  after.clear();
  expectOncePerEpoch(run(sparse_gsa, &after), 20, {5}, "GSA every 5th cycle");
}

// Steady state: no heap allocation per sentence (the handler here does not
// allocate either).
TEST(NmeaEpoch, NoAllocationPerSentence) {
  const std::string bytes = readFile(dataPath("ublox-zed-f9p-nmea.log")) + readFile(dataPath("nmea-rtk.log")) +
                            readFile(dataPath("gp-320fw-2019-04-07-coldboot.log"));
  struct Count final : NmeaDecoder::Handler {
    long fixes = 0, diags = 0;
    void onFix(const Fix&) override { ++fixes; }
    void onDiagnostic(const NmeaDiagnostic&) override { ++diags; }
  } c;
  NmeaDecoder dec;
  {
    blvd_test::AllocCounter check;  // the counter itself works
    std::string big(1000, 'x');
    EXPECT_GT(check.count(), 0);
  }
  blvd_test::AllocCounter counting;
  for (size_t i = 0; i < bytes.size(); i += 100) dec.feed(bytes.data() + i, std::min<size_t>(100, bytes.size() - i), c);
  dec.finish(c);
  EXPECT_EQ(counting.count(), 0);
  EXPECT_GT(c.fixes, 150);
  EXPECT_GT(c.diags, 20);
}

TEST(NmeaFix, Iso8601RoundTrip) {
  char t[40];
  const double v = static_cast<double>(daysFromCivil(2019, 4, 7)) * 86400.0 + 12 * 3600 + 34 * 60 + 56.5;
  EXPECT_EQ(formatIso8601(v, t, sizeof t), 24u);
  EXPECT_STREQ(t, "2019-04-07T12:34:56.500Z");
  double back = 0;
  ASSERT_TRUE(parseIso8601(t, 24, &back));
  EXPECT_DOUBLE_EQ(back, v);
  EXPECT_FALSE(parseIso8601("2019-04-07 12:34:56Z", 20, &back));
  EXPECT_EQ(formatIso8601(std::nan(""), t, sizeof t), 0u);
}

}  // namespace
