#include "gnss_feed.h"

#include <cstdio>

#include "gnss/to_blvd.h"


namespace vcan_drive {


struct GnssFeed::Out final : blvd::gnss::NmeaDecoder::Handler {
  GnssFeed* feed = nullptr;
  void onFix(const blvd::gnss::Fix& f) override {
    if (!(f.flags & blvd::gnss::kFixHasTime)) {
      ++feed->untimed_;
      return;
    }
    blvd_gnss_fix g = blvd::gnss::toBlvd(f);
    g.t += feed->offset_s_;
    feed->pending_.push_back(g);
  }
  void onDiagnostic(const blvd::gnss::NmeaDiagnostic& d) override {
    if (feed->diagnostics_++ < 10) std::fprintf(stderr, "vcan_drive: %s: %s\n", feed->path_.c_str(), d.message);
  }
};

blvd_status GnssFeed::open(const std::string& path, double offset_s, std::string& err) {
  in_.open(path, std::ios::binary);
  if (!in_) {
    err = path + ": cannot open";
    return BLVD_ERR_IO;
  }
  path_ = path;
  offset_s_ = offset_s;
  return BLVD_OK;
}

bool GnssFeed::readMore() {
  if (eof_) return false;
  char buf[4096];
  Out out;
  out.feed = this;
  in_.read(buf, sizeof buf);
  if (in_.gcount() > 0) decoder_.feed(buf, static_cast<size_t>(in_.gcount()), out);
  if (!in_) {
    decoder_.finish(out);
    eof_ = true;
  }
  return true;
}

bool GnssFeed::first(blvd_gnss_fix& out) {
  while (pending_.empty() && readMore()) {
  }
  if (pending_.empty()) return false;
  out = pending_.front();
  return true;
}

void GnssFeed::feedUntil(double trace_t, double to_rx, Tracking& tracking) {
  for (;;) {
    while (pending_.empty() && readMore()) {
    }
    if (pending_.empty() || pending_.front().t > trace_t) return;
    blvd_gnss_fix g = pending_.front();
    pending_.pop_front();
    g.t += to_rx;
    if (tracking.feedGnss(g) == BLVD_OK) ++fed_;
  }
}

}  // namespace vcan_drive
