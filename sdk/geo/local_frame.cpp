#include "geo/local_frame.h"

#include <GeographicLib/LocalCartesian.hpp>

namespace blvd::geo {

struct LocalFrame::Impl {
  GeographicLib::LocalCartesian lc;
};

LocalFrame::LocalFrame(double lat0, double lon0, double h0)
    : impl_(new Impl{GeographicLib::LocalCartesian(lat0, lon0, h0)}), lat0_(lat0), lon0_(lon0), h0_(h0) {}
LocalFrame::~LocalFrame() = default;
LocalFrame::LocalFrame(const LocalFrame& o) : impl_(new Impl(*o.impl_)), lat0_(o.lat0_), lon0_(o.lon0_), h0_(o.h0_) {}
LocalFrame& LocalFrame::operator=(const LocalFrame& o) {
  if (this != &o) {
    impl_.reset(new Impl(*o.impl_));
    lat0_ = o.lat0_;
    lon0_ = o.lon0_;
    h0_ = o.h0_;
  }
  return *this;
}

Enu LocalFrame::forward(double lat, double lon, double h) const {
  Enu p;
  impl_->lc.Forward(lat, lon, h, p.e, p.n, p.u);
  return p;
}

void LocalFrame::reverse(const Enu& p, double& lat, double& lon, double& h) const {
  impl_->lc.Reverse(p.e, p.n, p.u, lat, lon, h);
}

}  // namespace blvd::geo
