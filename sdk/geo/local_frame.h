// Geodetic <-> local east/north/up frame of a package (GeographicLib
// LocalCartesian on the WGS84 ellipsoid). Every package stores its origin;
// all bake and runtime geometry lives in this frame, in metres.
#pragma once
#include <memory>

namespace blvd::geo {

struct Enu {
  double e = 0, n = 0, u = 0;
};

class LocalFrame {
 public:
  LocalFrame(double lat0, double lon0, double h0 = 0);
  ~LocalFrame();
  LocalFrame(const LocalFrame&);
  LocalFrame& operator=(const LocalFrame&);

  Enu forward(double lat, double lon, double h = 0) const;
  void reverse(const Enu& p, double& lat, double& lon, double& h) const;

  double lat0() const { return lat0_; }
  double lon0() const { return lon0_; }
  double h0() const { return h0_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  double lat0_, lon0_, h0_;
};

}  // namespace blvd::geo
