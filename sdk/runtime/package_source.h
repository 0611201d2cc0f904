// Where a runtime's or a tracker's package comes from: a local file, or a
// server (an http:// or https:// URL) through a table mirror and a disk
// cache (remote/remote_package.h), with the blvd_runtime_desc link fields.
#pragma once
#include <cstdint>
#include <string>

#include "blvd/blvd.h"
#include "core/status.h"
#include "remote/remote_package.h"
#include "stream/city.h"

namespace blvd::runtime {

struct LinkDesc {
  const char* cache_path = nullptr;  // NULL: defaultCachePath()
  uint64_t cache_bytes = 0;          // 0: 256 MiB
  uint64_t max_bytes_per_s = 0;      // 0: no cap
  uint32_t mode = 0;                 // a blvd_link_mode
};

inline LinkDesc linkDesc(const blvd_runtime_desc& d) {
  return LinkDesc{d.cache_path, d.cache_bytes, d.link_max_bytes_per_s, d.link_mode};
}
inline LinkDesc linkDesc(const blvd_tracker_desc& d) {
  return LinkDesc{d.cache_path, d.cache_bytes, d.link_max_bytes_per_s, d.link_mode};
}

// $XDG_CACHE_HOME/blvd, else $HOME/.cache/blvd, else /tmp/blvd-cache.
std::string defaultCachePath();

// The link fields as the remote reader takes them; throws core::Error
// (InvalidArg) for an unknown mode.
remote::RemoteOptions remoteOptions(const LinkDesc& link);

// Opens `path` (a file or a URL) paged, throwing core::Error with the
// reader's message on failure.
void openCity(stream::City& city, const char* path, const LinkDesc& link, stream::City::Tables tables);

}  // namespace blvd::runtime
