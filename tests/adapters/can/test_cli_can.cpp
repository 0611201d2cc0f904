// `blvd can decode` / `blvd can odometry`, run through the same CLI11 hook the
// blvd tool uses (sdk/cli/cmd_can.cpp is compiled into this test).
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <sstream>

#include "can_test_util.h"
#include "cli/commands.h"

namespace blvd::can {
namespace {

std::string tempPath(const char* name) { return std::string(BLVD_BINARY_DIR) + "/test_can_cli_" + name; }

int runCli(std::vector<std::string> args) {
  CLI::App app{"blvd"};
  app.require_subcommand(1);
  blvd::cli::Runner run;
  blvd::cli::addCan(app, run);
  std::vector<const char*> argv{"blvd"};
  for (const auto& a : args) argv.push_back(a.c_str());
  try {
    app.parse(static_cast<int>(argv.size()), argv.data());
  } catch (const CLI::ParseError& e) {
    return 100 + app.exit(e);
  }
  return run ? run() : -1;
}

std::vector<std::string> lines(const std::string& path) {
  std::istringstream in(test::readFile(path));
  std::vector<std::string> out;
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

TEST(CanCli, DecodeJson) {
  // The first frames of the comma2k19 log, plus one of an id the DBC lacks.
  const std::string log = tempPath("in.log");
  {
    std::ofstream f(log);
    f << "(46408.584930) can0 260#08FFFB0000001884\n"
         "(46408.584954) can0 0B4#000000001D0B7A5E\n"
         "(46408.584959) can0 025#00001000C00000FD\n"
         "(46408.584960) can0 7E8#0102\n";
  }
  const std::string out = tempPath("out.jsonl");
  ASSERT_EQ(runCli({"can", "decode", log, "--dbc", test::dataPath("dbc/toyota_new_mc_pt_generated.dbc"), "--json",
                    "-o", out}),
            0);
  const auto l = lines(out);
  ASSERT_EQ(l.size(), 3u);
  EXPECT_EQ(l[1],
            "{\"t\":46408.584954,\"id\":180,\"iface\":\"can0\",\"name\":\"SPEED\",\"signals\":{\"ENCODER\":29,"
            "\"SPEED\":29.38,\"CHECKSUM\":94}}");
  EXPECT_EQ(l[2].rfind("{\"t\":46408.584959,\"id\":37,\"iface\":\"can0\",\"name\":\"STEER_ANGLE_SENSOR\","
                       "\"signals\":{\"STEER_ANGLE\":0,\"STEER_FRACTION\":-0.4,",
                       0),
            0u)
      << l[2];
  // Text mode names units and value descriptions.
  ASSERT_EQ(runCli({"can", "decode", log, "--dbc", test::dataPath("dbc/toyota_new_mc_pt_generated.dbc"), "-o", out}),
            0);
  EXPECT_EQ(lines(out)[1], "46408.584954 can0 0B4#000000001D0B7A5E SPEED ENCODER=29 SPEED=29.38 km/h CHECKSUM=94");
}

// A DBC as projects ship it: the messages the decoder cannot use are skipped
// (--strict refuses the file); a multiplexed message decodes, with its named values.
TEST(CanCli, FieldDbcSkipsOrRefusesAndNamesValues) {
  const std::string log = tempPath("field.log");
  {
    std::ofstream f(log);
    f << "(1.000000) can0 400#0250123400000000\n"  // RADAR_TRACK, track 2
         "(1.000001) can0 401#0229\n";             // RADAR_STATUS: tracking, 1 degC
  }
  const std::string out = tempPath("field.jsonl"), dbc = test::dataPath("dbc_cases/multiplexed.dbc");
  ASSERT_EQ(runCli({"can", "decode", log, "--dbc", dbc, "--json", "-o", out}), 0);
  const auto l = lines(out);
  ASSERT_EQ(l.size(), 2u);
  EXPECT_EQ(l[0], "{\"t\":1.000000,\"id\":1024,\"iface\":\"can0\",\"name\":\"RADAR_TRACK\",\"signals\":"
                  "{\"TRACK_ID\":2,\"STATUS\":5,\"RANGE_2\":46.6}}");
  EXPECT_EQ(l[1], "{\"t\":1.000001,\"id\":1025,\"iface\":\"can0\",\"name\":\"RADAR_STATUS\",\"signals\":"
                  "{\"MODE\":2,\"TEMPERATURE\":1},\"named\":{\"MODE\":\"tracking\"}}");
  EXPECT_EQ(runCli({"can", "decode", log, "--dbc", dbc, "--strict", "-o", out}), 2);
}

TEST(CanCli, BadLinesAndBadDbc) {
  const std::string out = tempPath("bad.jsonl");
  EXPECT_EQ(runCli({"can", "decode", test::dataPath("candump/bad_lines.log"), "--dbc",
                    test::dataPath("dbc/toyota_new_mc_pt_generated.dbc"), "--json", "-o", out}),
            1);  // 12 bad lines: reported with their numbers, skipped, exit status 1
  EXPECT_EQ(runCli({"can", "decode", test::dataPath("candump/bad_lines.log"), "--dbc", "/nonexistent.dbc"}), 2);
  EXPECT_EQ(runCli({"can", "decode", test::dataPath("candump/bad_lines.log")}), 100 + 106);  // --dbc is required
}

TEST(CanCli, OdometryOnTheComma2k19Log) {
  const std::string log = tempPath("comma2k19.log");
  {
    std::ofstream f(log, std::ios::binary);
    f << test::comma2k19Candump();
  }
  const std::string out = tempPath("odo.jsonl");
  ASSERT_EQ(runCli({"can", "odometry", log, "--dbc", test::dataPath("dbc/toyota_new_mc_pt_generated.dbc"),
                    "--vehicle", "toyota", "--iface", "can0", "--json", "-o", out}),
            0);
  const auto l = lines(out);
  EXPECT_GT(l.size(), 15000u);
  // The first row of the reference CSV: t 46408.589503, speed 7.974306, wheels 8.016667 8.016667 7.905556 7.958333.
  bool found = false;
  for (const auto& s : l)
    if (s.rfind("{\"t\":46408.589503,", 0) == 0) {
      found = true;
      EXPECT_NE(s.find("\"speed_mps\":7.97430"), std::string::npos) << s;
      EXPECT_NE(s.find("\"wheel_speeds_mps\":[8.01666"), std::string::npos) << s;
    }
  EXPECT_TRUE(found);
  std::remove(log.c_str());
  EXPECT_EQ(runCli({"can", "odometry", log, "--dbc", test::dataPath("dbc/toyota_new_mc_pt_generated.dbc"),
                    "--vehicle", "tesla"}),
            2);
}

}  // namespace
}  // namespace blvd::can
