// The tests read files with the same helpers as `blvd bench` (sdk/cli/read_files.h).
#pragma once

#include "cli/read_files.h"

namespace blvd::test {
using cli::readFile;
using cli::readZstd;
}  // namespace blvd::test
