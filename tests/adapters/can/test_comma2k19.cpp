// The check of decoding the comma2k19 RAV4 candump with the Toyota DBC
// reproduces comma's reference CSV exactly, every one of its 4,974 rows.
//
// Each CSV row belongs to one WHEEL_SPEEDS (0xAA) frame on can0 and carries its
// timestamp; rows are matched to frames by that timestamp, as text. Per row:
//   wheel_speed_xx_mps = WHEEL_SPEEDS.WHEEL_SPEED_XX / 3.6
//   speed_mps          = the mean of the four (openpilot's vEgoRaw; SPEED 0xB4 is the dashboard speed)
//   steering_angle_deg = STEER_ANGLE + STEER_FRACTION of the latest STEER_ANGLE_SENSOR (0x25) frame
// Frames that share a timestamp came in one batch (one panda USB read), and comma
// decoded a batch as a whole: a row holds the state after every frame of its
// timestamp, even one logged after the WHEEL_SPEEDS frame (two rows depend on
// that: at 46459.789246 and 46463.432948 a STEER_ANGLE_SENSOR frame follows the
// WHEEL_SPEEDS frame of the same batch). Both checks below read the log in batches.
// "Exactly" means: printed with the CSV's own number of decimals, our value is the
// CSV's text, and numerically it is within 1e-6 (relative, or absolute below 1).
// This is checked twice: with the DBC decoder directly, and through the Toyota profile.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <sstream>

#include "can/candump.h"
#include "vehicle/dbc.h"
#include "vehicle/profile.h"
#include "can_test_util.h"

namespace blvd::can {
namespace {

// The DBC subset and the profiles are the SDK's sdk/vehicle module; the candump
// reader that feeds these tests is the adapter's.
using namespace blvd::vehicle;

struct Row {
  std::string field[7];  // t, speed, steering, fl, fr, rl, rr as text
  int hits = 0;
};

std::map<std::string, Row> readReference() {
  std::istringstream in(test::readFile(test::dataPath("comma2k19_rav4_seg40_can_reference.csv")));
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line,
            "t_boot_s,speed_mps,steering_angle_deg,wheel_speed_fl_mps,wheel_speed_fr_mps,wheel_speed_rl_mps,"
            "wheel_speed_rr_mps");
  std::map<std::string, Row> rows;
  while (std::getline(in, line)) {
    Row r;
    std::istringstream ls(line);
    for (auto& f : r.field) std::getline(ls, f, ',');
    EXPECT_TRUE(rows.emplace(r.field[0], r).second) << "duplicate time " << r.field[0];
  }
  return rows;
}

std::string stamp(const Record& r) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%lld.%0*u", static_cast<long long>(r.sec), r.frac_digits, r.frac);
  return buf;
}

// Our value printed like the CSV field (same number of decimals).
std::string printedLike(double v, const std::string& csv) {
  const size_t dot = csv.find('.');
  const int decimals = dot == std::string::npos ? 0 : static_cast<int>(csv.size() - dot - 1);
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

// Reads a candump log in batches of frames with the same timestamp.
class BatchReader {
 public:
  explicit BatchReader(const std::string& text) : in_(text) { reader_.attach(in_, "comma2k19_rav4_seg40_candump.log"); }
  bool next(std::vector<Record>& batch) {
    batch.clear();
    if (have_) batch.push_back(ahead_);
    have_ = false;
    while (reader_.next(ahead_) == CandumpReader::Result::Frame) {
      if (!batch.empty() && (ahead_.sec != batch[0].sec || ahead_.frac != batch[0].frac)) {
        have_ = true;
        return true;
      }
      batch.push_back(ahead_);
    }
    return !batch.empty();
  }
  const CandumpReader& reader() const { return reader_; }

 private:
  std::istringstream in_;
  CandumpReader reader_;
  Record ahead_;
  bool have_ = false;
};

struct Tally {
  size_t rows = 0, values = 0, text_equal = 0, within_1e6 = 0;
  double max_abs_err = 0;
};

void compare(double ours, const std::string& csv, const std::string& what, const std::string& t, Tally& tally) {
  ++tally.values;
  const double ref = std::stod(csv);
  const double err = std::fabs(ours - ref);
  tally.max_abs_err = std::max(tally.max_abs_err, err);
  if (printedLike(ours, csv) == csv) ++tally.text_equal;
  else ADD_FAILURE() << "t=" << t << " " << what << ": ours " << printedLike(ours, csv) << ", CSV " << csv;
  if (err <= 1e-6 * std::max(1.0, std::fabs(ref))) ++tally.within_1e6;
  else ADD_FAILURE() << "t=" << t << " " << what << ": |" << ours << " - " << csv << "| = " << err;
}

void checkRow(Row& row, const std::string& t, double speed, double steer, const double wheels[4], Tally& tally) {
  ++row.hits;
  ++tally.rows;
  compare(speed, row.field[1], "speed_mps", t, tally);
  compare(steer, row.field[2], "steering_angle_deg", t, tally);
  static const char* kNames[] = {"wheel_speed_fl_mps", "wheel_speed_fr_mps", "wheel_speed_rl_mps",
                                 "wheel_speed_rr_mps"};
  for (int i = 0; i < 4; ++i) compare(wheels[i], row.field[3 + i], kNames[i], t, tally);
}

void report(const char* how, const Tally& t, size_t csv_rows) {
  std::printf("%s: %zu of %zu CSV rows matched, %zu values: %zu print identically, %zu within 1e-6, max |err| %.3g\n",
              how, t.rows, csv_rows, t.values, t.text_equal, t.within_1e6, t.max_abs_err);
}

class Comma2k19 : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string err;
    ASSERT_EQ(db_.load(test::dataPath("dbc/toyota_new_mc_pt_generated.dbc"), err), blvd::core::Status::Ok) << err;
    rows_ = readReference();
    ASSERT_EQ(rows_.size(), 4974u);
  }
  Database db_;
  std::map<std::string, Row> rows_;
};

TEST_F(Comma2k19, DbcDecodeReproducesTheReferenceCsv) {
  const Message* wheels = db_.findByName("WHEEL_SPEEDS");
  const Message* steer = db_.findByName("STEER_ANGLE_SENSOR");
  ASSERT_TRUE(wheels && steer);
  ASSERT_EQ(wheels->id, 0xAAu);
  ASSERT_EQ(steer->id, 0x25u);
  BatchReader batches(test::comma2k19Candump());
  std::vector<Record> batch;
  std::vector<DecodedSignal> sig;
  double steering = NAN;
  Tally tally;
  size_t wheel_frames = 0;
  while (batches.next(batch)) {
    const Record* wheel_record = nullptr;
    double w[4] = {NAN, NAN, NAN, NAN};
    for (const Record& r : batch) {
      if (r.frame.iface != "can0") continue;
      const Message* m = db_.find(r.frame);
      if (m == steer) {
        decode(*m, r.frame, sig);
        double angle = NAN, fraction = NAN;
        for (const auto& d : sig) {
          if (d.signal->name == "STEER_ANGLE") angle = d.value;
          if (d.signal->name == "STEER_FRACTION") fraction = d.value;
        }
        steering = angle + fraction;
      } else if (m == wheels) {
        ASSERT_EQ(wheel_record, nullptr) << "two WHEEL_SPEEDS frames in one batch, line " << r.line;
        wheel_record = &r;
        ++wheel_frames;
        decode(*m, r.frame, sig);
        for (const auto& d : sig) {
          const std::string& n = d.signal->name;
          const int i = n == "WHEEL_SPEED_FL" ? 0 : n == "WHEEL_SPEED_FR" ? 1 : n == "WHEEL_SPEED_RL" ? 2 : 3;
          w[i] = d.value / 3.6;
        }
      }
    }
    if (!wheel_record) continue;
    const double speed = (w[0] + w[1] + w[2] + w[3]) / 4;
    const std::string t = stamp(*wheel_record);
    const auto it = rows_.find(t);
    ASSERT_NE(it, rows_.end()) << "WHEEL_SPEEDS frame at " << t << " (line " << wheel_record->line
                               << ") has no CSV row";
    checkRow(it->second, t, speed, steering, w, tally);
  }
  const CandumpReader& reader = batches.reader();
  EXPECT_EQ(reader.badLineCount(), 0u);
  EXPECT_EQ(wheel_frames, 4974u);
  for (const auto& [t, row] : rows_) EXPECT_EQ(row.hits, 1) << "CSV row " << t;
  EXPECT_EQ(tally.rows, 4974u);
  EXPECT_EQ(tally.text_equal, tally.values);
  EXPECT_EQ(tally.within_1e6, tally.values);
  report("DBC decode", tally, rows_.size());
}

TEST_F(Comma2k19, ToyotaProfileReproducesTheReferenceCsv) {
  ProfileDesc desc;
  desc.vehicle = Vehicle::Toyota;
  desc.iface = "can0";
  Profile profile;
  std::string err;
  ASSERT_EQ(profile.create(desc, db_, err), blvd::core::Status::Ok) << err;
  BatchReader batches(test::comma2k19Candump());
  std::vector<Record> batch;
  Odometry odo;
  Tally tally;
  size_t updates = 0;
  double min_yaw = 1e9, max_yaw = -1e9, dash_ratio_sum = 0;
  size_t dash_n = 0;
  while (batches.next(batch)) {
    uint32_t updated = 0;  // what the batch changed
    for (const Record& r : batch) {
      if (!profile.consume(r.frame, odo)) continue;
      ++updates;
      updated |= odo.updated;
      EXPECT_EQ(odo.t, r.frame.t);
      if (odo.updated & kOdoYawRate) {
        min_yaw = std::min(min_yaw, odo.yaw_rate_dps);
        max_yaw = std::max(max_yaw, odo.yaw_rate_dps);
      }
    }
    if (!(updated & kOdoWheelSpeeds)) continue;
    const Odometry& s = profile.state();  // after the whole batch
    ASSERT_TRUE(updated & kOdoSpeed);
    ASSERT_TRUE(s.valid & kOdoSteering);
    if (s.valid & kOdoVehicleSpeed) {
      dash_ratio_sum += s.vehicle_speed_mps / s.speed_mps;
      ++dash_n;
    }
    const std::string t = stamp(batch[0]);
    const auto it = rows_.find(t);
    ASSERT_NE(it, rows_.end()) << "update at " << t << " has no CSV row";
    checkRow(it->second, t, s.speed_mps, s.steering_deg, s.wheel_speeds_mps, tally);
  }
  odo = profile.state();
  for (const auto& [t, row] : rows_) EXPECT_EQ(row.hits, 1) << "CSV row " << t;
  EXPECT_EQ(tally.rows, 4974u);
  EXPECT_EQ(tally.text_equal, tally.values);
  EXPECT_EQ(tally.within_1e6, tally.values);
  report("Toyota profile", tally, rows_.size());
  // Plausibility of what the CSV does not cover: a highway minute, in drive, gentle curves,
  // and the dashboard speed a few percent above the wheel speeds on average.
  EXPECT_TRUE(odo.valid & kOdoGear);
  EXPECT_EQ(odo.gear, Gear::Drive);
  EXPECT_GT(min_yaw, -10);
  EXPECT_LT(max_yaw, 10);
  ASSERT_GT(dash_n, 0u);
  const double dash_gap = dash_ratio_sum / static_cast<double>(dash_n) - 1;
  EXPECT_GT(dash_gap, 0.01);  // SOURCES.md: SPEED reads ~2.3 % above the wheel speeds
  EXPECT_LT(dash_gap, 0.04);
  std::printf("Toyota profile: %zu updates, yaw rate %.2f..%.2f deg/s, dashboard speed %.1f %% above wheel speed\n",
              updates, min_yaw, max_yaw, 100 * dash_gap);
}

}  // namespace
}  // namespace blvd::can
