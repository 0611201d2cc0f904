// Where the samples find the SDK's data files when no path is given: the
// vehicle DBC files (opendbc, MIT) that the SDK installs under
// <prefix>/share/blvd/dbc and keeps in the source tree under tests/data/can/dbc.
// Header-only; target blvd_sample_data (CMakeLists.txt) compiles in the places.
//
// defaultDbc(NAME), the default of a sample's --dbc (an explicit --dbc wins):
//   1. $BLVD_DATA_DIR/dbc/NAME when BLVD_DATA_DIR is set, whether or not the
//      file is there (a wrong setting then shows in the load error);
//   2. the first of the compiled-in folders (BLVD_SAMPLE_DBC_DIRS) that holds NAME:
//      in-tree build: the source tree's tests/data/can/dbc, then the install
//      prefix's share/blvd/dbc; built against an installed SDK: that SDK's
//      share/blvd/dbc (blvd_DATA_DIR), then the source tree's;
//   3. else NAME in the first of those folders, for the error message.
#pragma once

#include <sys/stat.h>

#include <cstdlib>
#include <string>

#ifndef BLVD_SAMPLE_DBC_DIRS
#error "link blvd_sample_data (samples/common/CMakeLists.txt)"
#endif

namespace blvd::samples {

inline std::string defaultDbc(const std::string& name) {
  if (const char* env = std::getenv("BLVD_DATA_DIR"); env && *env) return std::string(env) + "/dbc/" + name;
  const std::string dirs = BLVD_SAMPLE_DBC_DIRS;  // ':'-separated
  std::string first;
  for (size_t b = 0; b <= dirs.size();) {
    size_t e = dirs.find(':', b);
    if (e == std::string::npos) e = dirs.size();
    const std::string path = dirs.substr(b, e - b) + "/" + name;
    if (e > b) {
      struct stat st {};
      if (::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode)) return path;
      if (first.empty()) first = path;
    }
    b = e + 1;
  }
  return first.empty() ? name : first;
}

}  // namespace blvd::samples
