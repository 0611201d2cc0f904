// The range client against a real nginx (ranges, ETag, If-Match, a package
// replaced on the server, limit_rate) and against fault_server.py (a body
// cut mid-way, 200 to a range request, 503 with Retry-After, a stall, an
// ETag that changes), and against a port where nobody listens.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "remote/range_client.h"
#include "servers.h"

using namespace blvd;
namespace fs = std::filesystem;

namespace {

std::vector<uint8_t> pattern(size_t n, uint32_t seed) {
  std::vector<uint8_t> v(n);
  uint32_t x = seed;
  for (auto& b : v) x = x * 1664525u + 1013904223u, b = uint8_t(x >> 24);
  return v;
}

void writeFile(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::ofstream f(path + ".new", std::ios::binary);
  f.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  f.close();
  fs::rename(path + ".new", path);  // as a server's package is replaced: atomically
}

double secondsOf(const std::function<void()>& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

class Remote : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    work_ = (fs::temp_directory_path() / ("blvd-remote-" + std::to_string(::getpid()))).string();
    fs::create_directories(work_ + "/www");
    fs::create_directories(work_ + "/nginx");
    fs::create_directories(work_ + "/fault");
    file_ = pattern(200000, 7);
    writeFile(work_ + "/www/city.blvd", file_);
    nginx_ = new test::ServerProcess;
    faults_ = new test::ServerProcess;
    if (!nginx_->startNginx(work_ + "/nginx", work_ + "/www", 100000, why_) ||
        !faults_->startFaultServer(work_ + "/fault", work_ + "/www", why_))
      ok_ = false;
  }
  static void TearDownTestSuite() {
    delete nginx_;
    delete faults_;
    fs::remove_all(work_);
  }
  void SetUp() override {
    if (!ok_) GTEST_FAIL() << why_;
  }
  static remote::LinkOptions quick() {
    remote::LinkOptions o;
    o.backoff_s = 0.05;
    o.stall_timeout_s = 1.0;
    return o;
  }
  std::vector<uint8_t> slice(size_t off, size_t n) { return {file_.begin() + long(off), file_.begin() + long(off + n)}; }

  static inline std::string work_, why_;
  static inline std::vector<uint8_t> file_;
  static inline test::ServerProcess *nginx_ = nullptr, *faults_ = nullptr;
  static inline bool ok_ = true;
};

}  // namespace

TEST_F(Remote, NginxServesExactRangesAndPinsTheEtag) {
  remote::RangeClient c(nginx_->url("/city.blvd"), quick());
  std::vector<uint8_t> out;
  std::string err;
  ASSERT_EQ(c.fetch(0, 100, out, err), core::Status::Ok) << err;
  EXPECT_EQ(out, slice(0, 100));
  EXPECT_FALSE(c.etag().empty());
  EXPECT_EQ(c.resourceBytes(), file_.size());
  ASSERT_EQ(c.fetch(123457, 5000, out, err), core::Status::Ok) << err;
  EXPECT_EQ(out, slice(123457, 5000));
  ASSERT_EQ(c.fetch(file_.size() - 1, 1, out, err), core::Status::Ok) << err;
  EXPECT_EQ(out, slice(file_.size() - 1, 1));
  EXPECT_EQ(c.stats().requests, 3u);
  EXPECT_EQ(c.stats().retries, 0u);
  EXPECT_EQ(c.stats().bytes, 5101u);
  EXPECT_EQ(c.fetch(file_.size() + 10, 10, out, err), core::Status::InvalidArg);
  EXPECT_NE(err.find("416"), std::string::npos) << err;
  remote::RangeClient gone(nginx_->url("/nothing.blvd"), quick());
  EXPECT_EQ(gone.fetch(0, 10, out, err), core::Status::NotFound);
  EXPECT_NE(err.find("nothing.blvd"), std::string::npos) << err;
}

TEST_F(Remote, APackageReplacedOnTheServerIsNoticedNeverMixed) {
  const std::string path = work_ + "/www/swap.blvd";
  writeFile(path, file_);
  remote::RangeClient c(nginx_->url("/swap.blvd"), quick());
  std::vector<uint8_t> out;
  std::string err;
  ASSERT_EQ(c.fetch(0, 1000, out, err), core::Status::Ok) << err;
  std::vector<uint8_t> v2 = pattern(file_.size() + 17, 99);
  writeFile(path, v2);
  EXPECT_EQ(c.fetch(1000, 1000, out, err), core::Status::Corrupt);
  EXPECT_TRUE(c.changed());
  EXPECT_NE(err.find("changed on the server"), std::string::npos) << err;
  EXPECT_TRUE(out.empty());
}

TEST_F(Remote, LimitRateAndTheClientsCapBoundTheThroughput) {
  // Lower bounds only, allowing a burst of socket buffers (128 KiB): the
  // whole 200 kB through nginx's 100 kB/s, or through the client's own cap,
  // cannot take under (200 000 - 131 072) / 100 000 = 0.69 s.
  std::vector<uint8_t> out;
  std::string err;
  const size_t n = file_.size();
  remote::RangeClient slow(nginx_->url("/slow/city.blvd"), quick());
  const double t_server = secondsOf([&] { ASSERT_EQ(slow.fetch(0, n, out, err), core::Status::Ok) << err; });
  EXPECT_EQ(out, file_);
  EXPECT_GT(t_server, 0.69);
  remote::LinkOptions capped = quick();
  capped.max_bytes_per_s = 100000;
  remote::RangeClient c(nginx_->url("/city.blvd"), capped);
  const double t_client = secondsOf([&] { ASSERT_EQ(c.fetch(0, n, out, err), core::Status::Ok) << err; });
  EXPECT_EQ(out, file_);
  EXPECT_GT(t_client, 0.69);
}

TEST_F(Remote, ABodyCutMidwayIsFetchedAgain) {
  remote::RangeClient c(faults_->url("/cut/city.blvd"), quick());
  std::vector<uint8_t> out;
  std::string err;
  ASSERT_EQ(c.fetch(5000, 20000, out, err), core::Status::Ok) << err;
  EXPECT_EQ(out, slice(5000, 20000));
  EXPECT_EQ(c.stats().retries, 1u);
}

TEST_F(Remote, AServerIgnoringRangeIsReadOnlyUpToTheRangesEnd) {
  remote::RangeClient c(faults_->url("/full200/city.blvd"), quick());
  std::vector<uint8_t> out;
  std::string err;
  ASSERT_EQ(c.fetch(100, 400, out, err), core::Status::Ok) << err;
  EXPECT_EQ(out, slice(100, 400));
  EXPECT_LT(c.stats().bytes, file_.size());  // the transfer stopped once the range was in
  ASSERT_EQ(c.fetch(190000, 10000, out, err), core::Status::Ok) << err;
  EXPECT_EQ(out, slice(190000, 10000));
}

TEST_F(Remote, RetryAfterIsHonoured) {
  remote::RangeClient c(faults_->url("/retry503/city.blvd"), quick());
  std::vector<uint8_t> out;
  std::string err;
  const double t = secondsOf([&] { ASSERT_EQ(c.fetch(0, 1000, out, err), core::Status::Ok) << err; });
  EXPECT_EQ(out, slice(0, 1000));
  EXPECT_EQ(c.stats().retries, 1u);
  EXPECT_GE(t, 0.95);  // Retry-After: 1, not the 0.05 s backoff
}

TEST_F(Remote, AStalledLinkTimesOutAndIsRetried) {
  remote::RangeClient c(faults_->url("/stall/city.blvd"), quick());
  std::vector<remote::LinkStats> seen;  // each attempt's stats, as the fetch goes on
  c.onAttempt([&](const remote::LinkStats& s) { seen.push_back(s); });
  std::vector<uint8_t> out;
  std::string err;
  ASSERT_EQ(c.fetch(0, 1000, out, err), core::Status::Ok) << err;
  EXPECT_EQ(out, slice(0, 1000));
  EXPECT_GE(c.stats().retries, 1u);
  ASSERT_EQ(seen.size(), c.stats().requests);
  for (size_t k = 0; k < seen.size(); ++k) EXPECT_EQ(seen[k].requests, k + 1);
  EXPECT_EQ(seen.front().retries, 1u);  // the stall: known as a retry before the next attempt starts
  EXPECT_EQ(seen.back().fetches, 1u);
}

TEST_F(Remote, AnEtagThatChangesMidDriveIsAChangedPackage) {
  remote::RangeClient c(faults_->url("/etag/city.blvd"), quick());
  std::vector<uint8_t> out;
  std::string err;
  ASSERT_EQ(c.fetch(0, 10, out, err), core::Status::Ok) << err;
  EXPECT_EQ(c.etag(), "\"v1\"");
  ASSERT_EQ(c.fetch(10, 10, out, err), core::Status::Ok) << err;
  EXPECT_EQ(c.fetch(20, 10, out, err), core::Status::Corrupt);
  EXPECT_TRUE(c.changed());
}

TEST_F(Remote, NobodyListeningGivesUpAfterTheAttemptsNamingTheUrl) {
  remote::LinkOptions o = quick();
  o.max_attempts = 3;
  remote::RangeClient c("http://127.0.0.1:" + std::to_string(test::freePort()) + "/city.blvd", o);
  std::vector<uint8_t> out;
  std::string err;
  EXPECT_EQ(c.fetch(0, 10, out, err), core::Status::Io);
  EXPECT_NE(err.find("gave up after 3 attempts"), std::string::npos) << err;
  EXPECT_NE(err.find("/city.blvd: bytes 0-9"), std::string::npos) << err;
  EXPECT_EQ(c.stats().requests, 3u);
  EXPECT_EQ(c.stats().retries, 2u);
}
