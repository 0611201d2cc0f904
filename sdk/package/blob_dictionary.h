// The built-in zstd dictionary of blob frames flagged kBlobZstdDict
// (package format 6.0; blob_dictionary.cpp holds its frozen bytes).
#pragma once
#include <cstddef>

namespace blvd::package {

struct BlobDictionary {
  const char* data;
  size_t size;
};

BlobDictionary glbDictionary();

}  // namespace blvd::package
