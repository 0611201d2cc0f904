// A package from a file or a server; the contract is in package_source.h.
#include "runtime/package_source.h"

#include <cstdlib>

namespace blvd::runtime {

std::string defaultCachePath() {
  if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) return std::string(x) + "/blvd";
  if (const char* h = std::getenv("HOME"); h && *h) return std::string(h) + "/.cache/blvd";
  return "/tmp/blvd-cache";
}

remote::RemoteOptions remoteOptions(const LinkDesc& link) {
  if (link.mode > BLVD_LINK_OFFLINE)
    throw core::Error(core::Status::InvalidArg, "link_mode " + std::to_string(link.mode) + " is not a blvd_link_mode");
  remote::RemoteOptions o;
  o.cache_path = link.cache_path && *link.cache_path ? link.cache_path : defaultCachePath();
  o.cache_bytes = link.cache_bytes ? link.cache_bytes : 256ull << 20;
  o.link.max_bytes_per_s = link.max_bytes_per_s;
  o.mode = static_cast<remote::LinkMode>(link.mode);
  return o;
}

void openCity(stream::City& city, const char* path, const LinkDesc& link, stream::City::Tables tables) {
  std::string err;
  const core::Status st = stream::City::isUrl(path)
                              ? city.openUrl(path, remoteOptions(link), err, tables, stream::City::GraphTables::Paged)
                              : city.open(path, err, tables, stream::City::GraphTables::Paged);
  if (st != core::Status::Ok) throw core::Error(st, err);
}

}  // namespace blvd::runtime
