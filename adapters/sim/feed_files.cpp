// makeFeed() from files: the package's street graph (City::Tables::Graph: no
// render data is read) and the vehicle's DBC bound to its profile.
#include <string>

#include "sim/sim_feed.h"
#include "stream/city.h"
#include "vehicle/dbc.h"

namespace blvd::sim {

blvd_status makeFeed(const FeedFiles& files, const FeedDesc& desc, Feed& out, std::string& err) {
  // core::Status carries the C API's values (core/status.h).
  const auto status = [](core::Status st) { return static_cast<blvd_status>(st); };
  stream::City city;
  if (const auto st = city.open(files.package_path, err, stream::City::Tables::Graph); st != core::Status::Ok)
    return status(st);
  vehicle::Database dbc;
  if (const auto st = dbc.load(files.dbc_path, err); st != core::Status::Ok) return status(st);
  vehicle::ProfileDesc pd;
  if (files.vehicle < BLVD_VEHICLE_TOYOTA || files.vehicle > BLVD_VEHICLE_HYUNDAI) {
    err = "unknown vehicle " + std::to_string(static_cast<int>(files.vehicle));
    return BLVD_ERR_INVALID_ARG;
  }
  pd.vehicle = static_cast<vehicle::Vehicle>(files.vehicle);
  vehicle::Profile profile;
  if (const auto st = profile.create(pd, dbc, err); st != core::Status::Ok) return status(st);
  return makeFeed(city.graph(), city.frame(), profile, desc, out, err);
}

}  // namespace blvd::sim
