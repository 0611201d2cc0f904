// candump log reader and writer: every frame kind, byte-identical round trips
// (hand-made edge cases and the whole comma2k19 log), bad lines named by line
// number and skipped, bounded memory on over-long lines.
#include <gtest/gtest.h>

#include <sstream>

#include "can/candump.h"
#include "can_test_util.h"

namespace blvd::can {
namespace {

Record parseOk(const std::string& line) {
  Record r;
  std::string reason;
  EXPECT_TRUE(parseLine(line, r, reason)) << line << ": " << reason;
  return r;
}

std::string parseFails(const std::string& line) {
  Record r;
  std::string reason;
  EXPECT_FALSE(parseLine(line, r, reason)) << line;
  EXPECT_FALSE(reason.empty());
  return reason;
}

TEST(Candump, ClassicStandard) {
  const Record r = parseOk("(1533198887.123456) can0 123#DEADBEEF");
  EXPECT_EQ(r.sec, 1533198887);
  EXPECT_EQ(r.frac, 123456u);
  EXPECT_DOUBLE_EQ(r.frame.t, 1533198887.123456);
  EXPECT_EQ(r.frame.iface, "can0");
  EXPECT_EQ(r.frame.id, 0x123u);
  EXPECT_FALSE(r.frame.extended);
  EXPECT_FALSE(r.frame.rtr || r.frame.error || r.frame.fd);
  ASSERT_EQ(r.frame.dlc, 4);
  EXPECT_EQ(r.frame.data[0], 0xDE);
  EXPECT_EQ(r.frame.data[3], 0xEF);
  EXPECT_EQ(formatFrame(r.frame), "123#DEADBEEF");
}

TEST(Candump, ExtendedRtrFdError) {
  Record r = parseOk("(1.000001) can0 12345678#00");
  EXPECT_TRUE(r.frame.extended);
  EXPECT_EQ(r.frame.id, 0x12345678u);
  EXPECT_EQ(r.frame.dlc, 1);

  r = parseOk("(1.000001) can0 123#R");
  EXPECT_TRUE(r.frame.rtr);
  EXPECT_EQ(r.frame.dlc, 0);
  r = parseOk("(1.000001) can0 123#r4");  // can-utils takes lowercase
  EXPECT_TRUE(r.frame.rtr);
  EXPECT_EQ(r.frame.dlc, 4);
  EXPECT_EQ(formatFrame(r.frame), "123#R4");
  r = parseOk("(1.000001) can0 1FFFFFFF#R8_9");
  EXPECT_TRUE(r.frame.extended && r.frame.rtr);
  EXPECT_EQ(r.frame.len8_dlc, 9);

  r = parseOk("(1.000001) can1 123##5DEADBEEF");
  EXPECT_TRUE(r.frame.fd);
  EXPECT_EQ(r.frame.fd_flags, kFdBrs | kFdFdf);
  EXPECT_EQ(r.frame.dlc, 4);
  r = parseOk("(1.000001) can1 123##1");
  EXPECT_TRUE(r.frame.fd);
  EXPECT_EQ(r.frame.dlc, 0);
  std::string fd64 = "(1.000001) can1 1ABCDEF0##4";
  for (int i = 0; i < 64; ++i) fd64 += "A5";
  r = parseOk(fd64);
  EXPECT_EQ(r.frame.dlc, 64);
  EXPECT_EQ(r.frame.data[63], 0xA5);

  r = parseOk("(1.000001) can0 20000040#0000000000000000");
  EXPECT_TRUE(r.frame.error);
  EXPECT_FALSE(r.frame.extended);
  EXPECT_EQ(r.frame.id, 0x40u);  // CAN_ERR_BUSOFF
  EXPECT_EQ(formatFrame(r.frame), "20000040#0000000000000000");

  r = parseOk("(1.000001) can0 123#1122334455667788_B");
  EXPECT_EQ(r.frame.dlc, 8);
  EXPECT_EQ(r.frame.len8_dlc, 11);

  r = parseOk("(1.000001) can0 123#de.ad.be.ef");  // separators and lowercase, as can-utils accepts
  EXPECT_EQ(formatFrame(r.frame), "123#DEADBEEF");
}

TEST(Candump, TimestampsAndColumns) {
  Record r = parseOk("(46408.584930) can128 2E4#BE000000A9");
  EXPECT_EQ(r.sec_width, 5);
  EXPECT_EQ(r.frame.iface, "can128");
  EXPECT_DOUBLE_EQ(r.frame.t, 46408.58493);
  r = parseOk("(1533198887.123456789) can0 123#00");
  EXPECT_EQ(r.frac_digits, 9);
  EXPECT_EQ(r.frac, 123456789u);
  r = parseOk("(1533198887.123471)   can0 321#01");  // candump right-aligns names when logging several
  EXPECT_EQ(r.frame.iface, "can0");
  EXPECT_EQ(r.iface_width, 6);
  r = parseOk("(1533198887.123473) can0 123#DEADBEEF R");
  EXPECT_EQ(r.direction, 'R');
  r = parseOk("(1533198887.123473) can0 123#DEADBEEF\r");
  EXPECT_EQ(r.frame.dlc, 4);
}

TEST(Candump, BadFramesSayWhy) {
  EXPECT_NE(parseFails("1533198887.123456 can0 123#00").find("timestamp"), std::string::npos);
  EXPECT_NE(parseFails("(1533198887.123456) can0 1234#00").find("3 or 8 hex digits"), std::string::npos);
  EXPECT_NE(parseFails("(1.5) can0 800#00").find("exceeds 7FF"), std::string::npos);
  EXPECT_NE(parseFails("(1.5) can0 123#DEADBEE").find("odd number"), std::string::npos);
  EXPECT_NE(parseFails("(1.5) can0 123#112233445566778899").find("longer than 8"), std::string::npos);
  EXPECT_NE(parseFails("(1.5) can0 123##0112233445566778899").find("cannot carry 9 bytes"), std::string::npos);
  EXPECT_NE(parseFails("(1.5) can0 123#R9").find("remote request length"), std::string::npos);
  EXPECT_NE(parseFails("(1.5) can0 123#00 extra").find("unexpected text"), std::string::npos);
  EXPECT_NE(parseFails("(1.5) can0 80000123#00").find("flag bits"), std::string::npos);
  EXPECT_NE(parseFails("(1.5) can0 20000040#R").find("error frame"), std::string::npos);
  EXPECT_NE(parseFails("(1.5) can0").find("no frame"), std::string::npos);
  EXPECT_NE(parseFails("(1.1234567890) can0 123#00").find("9 fraction digits"), std::string::npos);
}

TEST(Candump, EdgeCaseFileRoundTripsByteForByte) {
  const std::string text = test::readFile(test::dataPath("candump/edge_cases.log"));
  std::istringstream in(text);
  CandumpReader reader;
  reader.attach(in, "edge_cases.log");
  std::ostringstream out;
  CandumpWriter writer(out);
  Record r;
  CandumpReader::Result res;
  while ((res = reader.next(r)) == CandumpReader::Result::Frame) ASSERT_TRUE(writer.write(r));
  EXPECT_EQ(res, CandumpReader::Result::End) << reader.error();
  EXPECT_EQ(reader.badLineCount(), 0u);
  EXPECT_EQ(reader.frameCount(), 24u);
  EXPECT_EQ(out.str(), text);
}

TEST(Candump, BadLinesAreNamedAndSkipped) {
  CandumpReader reader;
  ASSERT_EQ(reader.open(test::dataPath("candump/bad_lines.log")), BLVD_OK) << reader.error();
  std::vector<uint64_t> good, bad;
  std::vector<std::string> errors;
  Record r;
  for (;;) {
    const auto res = reader.next(r);
    if (res == CandumpReader::Result::End) break;
    ASSERT_NE(res, CandumpReader::Result::IoError) << reader.error();
    if (res == CandumpReader::Result::Frame) {
      good.push_back(r.line);
    } else {
      bad.push_back(reader.lineNumber());
      errors.push_back(reader.error());
    }
  }
  EXPECT_EQ(good, (std::vector<uint64_t>{1, 15}));
  EXPECT_EQ(bad, (std::vector<uint64_t>{2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 13, 14}));  // 12 is blank
  ASSERT_FALSE(errors.empty());
  EXPECT_EQ(errors[0].rfind(test::dataPath("candump/bad_lines.log") + ":2: ", 0), 0u) << errors[0];
  EXPECT_NE(errors[3].find(":5: identifier must have 3 or 8 hex digits"), std::string::npos) << errors[3];
  EXPECT_EQ(reader.badLineCount(), 12u);
}

TEST(Candump, OverlongLineIsBoundedAndSkipped) {
  std::string text = "(1.000001) can0 111#01\n(1.000002) can0 222#";
  text.append(10 * 1024 * 1024, 'A');  // 10 MiB without a newline: must not be buffered whole
  text += "\n(1.000003) can0 333#03";     // and a last line without '\n'
  std::istringstream in(text);
  CandumpReader reader;
  reader.attach(in, "long");
  Record r;
  ASSERT_EQ(reader.next(r), CandumpReader::Result::Frame);
  EXPECT_EQ(r.frame.id, 0x111u);
  ASSERT_EQ(reader.next(r), CandumpReader::Result::BadLine);
  EXPECT_EQ(reader.error(), "long:2: line longer than 1024 bytes");
  ASSERT_EQ(reader.next(r), CandumpReader::Result::Frame);
  EXPECT_EQ(r.frame.id, 0x333u);
  EXPECT_EQ(r.line, 3u);
  EXPECT_EQ(reader.next(r), CandumpReader::Result::End);
}

TEST(Candump, MissingFileIsAnIoError) {
  CandumpReader reader;
  EXPECT_EQ(reader.open("/nonexistent/x.log"), BLVD_ERR_IO);
  EXPECT_NE(reader.error().find("/nonexistent/x.log: cannot open"), std::string::npos);
}

TEST(Candump, WriterCanonicalFromFrame) {
  Frame f;
  f.t = 1533198887.123456;
  f.id = 0x1B4;
  f.dlc = 2;
  f.data[0] = 0x0A;
  f.data[1] = 0xFF;
  EXPECT_EQ(formatLine(f), "(1533198887.123456) can0 1B4#0AFF");
  f.iface = "vcan0";
  f.t = 2.9999996;  // rounds up into the next second
  EXPECT_EQ(formatLine(f), "(0000000003.000000) vcan0 1B4#0AFF");
  // And what the writer writes, the reader reads back.
  Record r = parseOk(formatLine(f));
  EXPECT_EQ(r.frame.id, f.id);
  EXPECT_EQ(r.frame.dlc, f.dlc);
  EXPECT_EQ(r.frame.data[1], 0xFF);
}

TEST(Candump, Comma2k19LogRoundTripsByteForByte) {
  const std::string& text = test::comma2k19Candump();
  ASSERT_EQ(text.size(), 5381510u);  // the size SOURCES.md gives for the original
  std::istringstream in(text);
  CandumpReader reader;
  reader.attach(in, "comma2k19_rav4_seg40_candump.log");
  std::ostringstream out;
  CandumpWriter writer(out);
  Record r;
  CandumpReader::Result res;
  while ((res = reader.next(r)) == CandumpReader::Result::Frame) writer.write(r);
  EXPECT_EQ(res, CandumpReader::Result::End) << reader.error();
  EXPECT_EQ(reader.frameCount(), 135468u);
  EXPECT_EQ(reader.badLineCount(), 0u);
  EXPECT_TRUE(out.str() == text) << "round trip differs";
}

TEST(Candump, ScionLogFromSharedDataIfPresent) {
  // GPL-3.0: read in place from ../shared/data, never copied into the repository.
  const std::string path = test::sharedDataPath("can/scion_xb_mphlog.log");
  if (!test::exists(path)) GTEST_SKIP() << path << " not present";
  CandumpReader reader;
  ASSERT_EQ(reader.open(path), BLVD_OK) << reader.error();
  std::ostringstream out;
  CandumpWriter writer(out);
  Record r;
  CandumpReader::Result res;
  while ((res = reader.next(r)) == CandumpReader::Result::Frame) writer.write(r);
  EXPECT_EQ(res, CandumpReader::Result::End) << reader.error();
  EXPECT_EQ(reader.frameCount(), 8762u);
  EXPECT_EQ(reader.badLineCount(), 0u) << reader.error();
  EXPECT_TRUE(out.str() == test::readFile(path)) << "round trip differs";
}

}  // namespace
}  // namespace blvd::can
