// Determinism: a live session is recorded and the recording replayed twice on
// the same build, through the public C API with headless frames.
//
// The live session is the sim_feed Monaco drive (fixture sim_feed_trace) fed as
// a host would feed it (blvd_feed_gnss, blvd_feed_can_frame with a Toyota
// profile); every fix and frame is also written by adapters/replay's Recorder
// (NMEA + candump). Each replay reads the recording back the same way into a
// fresh runtime. At every NMEA epoch the pose is taken, and every few epochs a
// frame is rendered and its pixels hashed (FNV-1a 64 of blvd_read_pixels).
// Frames are drawn in BLVD_MODE_FULL: the streamed modes draw what the loader
// thread has made resident by then, which depends on scheduling (the timing
// is not part of the recording).
//
// Asserts: the two replays give bitwise-identical poses and identical frame
// hashes; the recording gives back every live input (fix and CAN frame) bit for
// bit; the replay's poses and frames equal the live session's bit for bit over
// the whole drive, the GNSS outage included (a difference names the first pose
// and field). The hash and the comparison are shown to fail: one changed pixel
// changes the hash, and one changed CAN payload changes the poses and frames of
// a replay.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "blvd/blvd.h"
#include "replay/recorder.h"
#include "trace_inputs.h"

namespace {

using namespace blvd::trace_test;

constexpr uint32_t kWidth = 160, kHeight = 96;
constexpr size_t kRenderEvery = 10;  // epochs between frames (10 s at the fixture's 1 Hz)

uint64_t fnv1a(const std::vector<uint8_t>& bytes) {
  uint64_t h = 1469598103934665603ull;
  for (uint8_t b : bytes) h = (h ^ b) * 1099511628211ull;
  return h;
}

struct Session {
  std::vector<blvd_pose> poses;   // one per epoch
  std::vector<uint64_t> hashes;   // one per kRenderEvery epochs
  size_t distinct_hashes = 0;
};

// Feeds `inputs` into a fresh runtime, sampling at `epochs`; with `rec`, every
// input is also recorded as it is fed.
Session run(const std::vector<Input>& inputs, const std::vector<double>& epochs, blvd::replay::Recorder* rec) {
  Session s;
  blvd_runtime_desc desc{};
  desc.struct_size = sizeof desc;
  desc.package_path = BLVD_TEST_PACKAGE;
  desc.width = kWidth;
  desc.height = kHeight;
  desc.mode = BLVD_MODE_FULL;
  blvd_runtime* rt = nullptr;
  EXPECT_EQ(blvd_runtime_create(&desc, &rt), BLVD_OK) << blvd_last_error(nullptr);
  if (rt) {
    EXPECT_EQ(blvd_set_camera_source(rt, BLVD_CAMERA_TRACKED), BLVD_OK);  // frames follow the feeds
  }
  blvd_can_profile* prof = createToyotaProfile();
  if (!rt || !prof) {
    blvd_can_profile_destroy(prof);
    blvd_runtime_destroy(rt);
    return s;
  }
  std::vector<uint8_t> rgba(size_t(kWidth) * kHeight * 4);
  size_t k = 0;
  for (size_t e = 0; e < epochs.size(); ++e) {
    for (; k < inputs.size() && inputs[k].t <= epochs[e] + 1e-6; ++k) {
      const Input& in = inputs[k];
      EXPECT_EQ(feed(rt, prof, in), BLVD_OK) << "input " << k;
      if (rec) {
        EXPECT_TRUE(in.gnss ? rec->record(in.fix) : rec->record(in.frame)) << "recording input " << k;
      }
    }
    blvd_pose p{};
    p.struct_size = sizeof p;
    EXPECT_EQ(blvd_get_pose(rt, epochs[e], &p), BLVD_OK) << blvd_last_error(rt);
    s.poses.push_back(p);
    if (e % kRenderEvery != 0) continue;
    blvd_frame_stats fs{};
    fs.struct_size = sizeof fs;
    EXPECT_EQ(blvd_render(rt, &fs), BLVD_OK) << blvd_last_error(rt);
    EXPECT_EQ(blvd_read_pixels(rt, rgba.data(), rgba.size()), BLVD_OK) << blvd_last_error(rt);
    s.hashes.push_back(fnv1a(rgba));
  }
  if (rec) {
    for (; k < inputs.size(); ++k) EXPECT_TRUE(inputs[k].gnss ? rec->record(inputs[k].fix) : rec->record(inputs[k].frame));
    EXPECT_TRUE(rec->flush());
  }
  std::vector<uint64_t> sorted = s.hashes;
  std::sort(sorted.begin(), sorted.end());
  s.distinct_hashes = size_t(std::unique(sorted.begin(), sorted.end()) - sorted.begin());
  blvd_can_profile_destroy(prof);
  blvd_runtime_destroy(rt);
  return s;
}

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// "" when equal bit for bit, else the first differing pose and field.
std::string firstDifference(const std::vector<blvd_pose>& a, const std::vector<blvd_pose>& b) {
  if (a.size() != b.size()) return "pose counts " + std::to_string(a.size()) + " vs " + std::to_string(b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    const blvd_pose &p = a[i], &q = b[i];
    const char* field = !sameBits(p.t, q.t)                       ? "t"
                        : !sameBits(p.x, q.x)                     ? "x"
                        : !sameBits(p.y, q.y)                     ? "y"
                        : !sameBits(p.lat, q.lat)                 ? "lat"
                        : !sameBits(p.lon, q.lon)                 ? "lon"
                        : !sameBits(p.heading_deg, q.heading_deg) ? "heading_deg"
                        : !sameBits(p.speed_mps, q.speed_mps)     ? "speed_mps"
                        : p.cell != q.cell                        ? "cell"
                        : !sameBits(p.arc_m, q.arc_m)             ? "arc_m"
                        : !sameBits(p.lateral_m, q.lateral_m)     ? "lateral_m"
                        : !sameBits(p.confidence, q.confidence)   ? "confidence"
                        : p.flags != q.flags                      ? "flags"
                                                                  : nullptr;
    if (field) {
      char buf[200];
      std::snprintf(buf, sizeof buf, "pose %zu (t %.3f): %s differs (x %.9g/%.9g, y %.9g/%.9g)", i, p.t, field, p.x, q.x,
                    p.y, q.y);
      return buf;
    }
  }
  return "";
}

bool sameFix(const blvd_gnss_fix& a, const blvd_gnss_fix& b) {
  return sameBits(a.t, b.t) && sameBits(a.lat, b.lat) && sameBits(a.lon, b.lon) && sameBits(a.alt, b.alt) &&
         sameBits(a.speed_mps, b.speed_mps) && sameBits(a.track_deg, b.track_deg) && sameBits(a.hdop, b.hdop) &&
         sameBits(a.h_acc_m, b.h_acc_m) && a.mode == b.mode && a.flags == b.flags;
}

bool sameFrame(const blvd::can::Frame& a, const blvd::can::Frame& b) {
  return sameBits(a.t, b.t) && a.id == b.id && a.extended == b.extended && a.dlc == b.dlc &&
         std::memcmp(a.data, b.data, a.dlc) == 0;
}

// The first input where the recording differs from what was fed live (a.size() when none).
size_t firstInputDifference(const std::vector<Input>& live, const std::vector<Input>& rec) {
  for (size_t i = 0; i < live.size(); ++i)
    if (i >= rec.size() || live[i].gnss != rec[i].gnss ||
        (live[i].gnss ? !sameFix(live[i].fix, rec[i].fix) : !sameFrame(live[i].frame, rec[i].frame)))
      return i;
  return live.size();
}

class Determinism : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    for (const Truth& t : readTruth(BLVD_SIM_TRACE ".csv")) epochs_.push_back(t.t);
    live_inputs_ = readInputs(BLVD_SIM_TRACE ".nmea", BLVD_SIM_TRACE ".log");
    blvd::replay::Recorder rec;
    std::string err;
    ASSERT_EQ(rec.openNmea(kRecNmea, err), BLVD_OK) << err;
    ASSERT_EQ(rec.openCandump(kRecCandump, err), BLVD_OK) << err;
    live_ = run(live_inputs_, epochs_, &rec);
    EXPECT_GT(rec.fixes(), 0u);
    EXPECT_EQ(rec.frames() + rec.fixes(), live_inputs_.size());
  }
  static constexpr const char* kRecNmea = BLVD_SIM_TRACE "-recorded.nmea";
  static constexpr const char* kRecCandump = BLVD_SIM_TRACE "-recorded.log";
  static std::vector<double> epochs_;
  static std::vector<Input> live_inputs_;
  static Session live_;
};
std::vector<double> Determinism::epochs_;
std::vector<Input> Determinism::live_inputs_;
Session Determinism::live_;

TEST(FrameHash, OnePixelChangesIt) {
  std::vector<uint8_t> a(size_t(kWidth) * kHeight * 4, 0x80);
  const uint64_t h = fnv1a(a);
  a[size_t(kWidth) * 40 * 4 + 7] ^= 1;  // one channel of one pixel, one bit
  EXPECT_NE(fnv1a(a), h);
}

TEST_F(Determinism, TwoReplaysOfTheRecordingAreIdentical) {
  ASSERT_GT(epochs_.size(), 120u);
  const std::vector<Input> recorded = readInputs(kRecNmea, kRecCandump);
  const Session a = run(recorded, epochs_, nullptr);
  const Session b = run(recorded, epochs_, nullptr);
  ASSERT_EQ(a.poses.size(), epochs_.size());
  EXPECT_EQ(firstDifference(a.poses, b.poses), "");
  EXPECT_EQ(a.hashes, b.hashes);
  // The frames are pictures of a moving drive, not one image over and over.
  EXPECT_GT(a.distinct_hashes, a.hashes.size() / 2) << "frames repeat: is the eye following the pose?";
  size_t matched = 0;
  for (const blvd_pose& p : a.poses) matched += (p.flags & BLVD_POSE_MATCHED) != 0;
  EXPECT_GT(matched, a.poses.size() * 9 / 10);
}

TEST_F(Determinism, ReplayEqualsLiveSession) {
  // The recording gives back every input as it was fed: the same fixes (one per
  // NMEA epoch, outage and dropped-fix epochs included) and CAN frames, bit for
  // bit, in the same order. So the replay is the live session over the whole
  // drive: every pose and every frame.
  const std::vector<Input> recorded = readInputs(kRecNmea, kRecCandump);
  ASSERT_EQ(recorded.size(), live_inputs_.size());
  const size_t d = firstInputDifference(live_inputs_, recorded);
  if (d < live_inputs_.size())
    ADD_FAILURE() << "input " << d << " of " << live_inputs_.size() << " (t " << std::fixed << live_inputs_[d].t
                  << ", " << (live_inputs_[d].gnss ? "a fix" : "a CAN frame") << ") was recorded differently";
  size_t fixes = 0, no_fix = 0;
  for (const Input& in : live_inputs_) {
    fixes += in.gnss;
    no_fix += in.gnss && in.fix.mode == 1;
  }
  std::printf("recording exact for %zu of %zu inputs (%zu fixes, %zu of them without a fix)\n", d, live_inputs_.size(),
              fixes, no_fix);
  EXPECT_EQ(fixes, epochs_.size()) << "one fix per NMEA epoch";
  EXPECT_GT(no_fix, 20u) << "the drive should have its outage";
  const Session a = run(recorded, epochs_, nullptr);
  ASSERT_EQ(a.poses.size(), epochs_.size());
  EXPECT_EQ(firstDifference(live_.poses, a.poses), "");
  EXPECT_EQ(live_.hashes, a.hashes);
}

TEST_F(Determinism, OneChangedFrameChangesTheReplay) {
  // The comparison above can fail: one WHEEL_SPEEDS payload early in the drive,
  // raised by 10 km/h on every wheel, moves the dead-reckoned pose.
  std::vector<Input> changed = readInputs(kRecNmea, kRecCandump);
  size_t i = 0;
  while (i < changed.size() && (changed[i].gnss || changed[i].frame.id != 0xAA || changed[i].t < epochs_[20])) ++i;
  ASSERT_LT(i, changed.size());
  for (int w = 0; w < 4; ++w)  // + 4 * 256 * 0.01 km/h per wheel
    changed[i].frame.data[2 * w] = static_cast<uint8_t>(changed[i].frame.data[2 * w] + 4);
  const Session c = run(changed, epochs_, nullptr);
  EXPECT_NE(firstDifference(live_.poses, c.poses), "");
  EXPECT_NE(live_.hashes, c.hashes);
}

}  // namespace
