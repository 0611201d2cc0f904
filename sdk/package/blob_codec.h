// How a blob is kept in the file (package format 4.0): as its contents (a
// GLB, a terrain tile's heights) or as one zstd frame of them, BIDX flag
// kBlobZstd; since 6.0 the frame may be made with the built-in dictionary of
// glTF JSON (kBlobZstdDict, blob_dictionary.h): an impostor layer's frame
// is 0.84 of its size without it (decision 0041). EXT_meshopt_compression's streams are made to be compressed
// again by a general-purpose compressor, and a GLB's JSON is text: on the
// 2016 Monaco route the blobs shrink to 0.67 of their size (decision 0029).
//
// The CRC in BIDX is of the stored bytes, so a range client checks what it
// fetched before it decompresses anything.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"
#include "package/format.h"
#include "package/reader.h"

namespace blvd::package {

struct StoredBlob {
  std::vector<uint8_t> bytes;  // what goes into BDAT
  uint32_t flags = 0;          // kBlobZstd (| kBlobZstdDict) or 0
  uint64_t contents_size = 0;
};

// `contents` as one zstd frame at `level` (1 to ZSTD_maxCLevel()), with the
// built-in dictionary or without, whichever is smaller, when that is smaller
// than the contents, else as is; level 0 keeps it as is. Throws core::Error
// (InvalidArg) for a level outside 0..22 or contents over
// kMaxBlobContentsBytes.
StoredBlob packBlob(std::vector<uint8_t> contents, int level);
// Throws as packBlob() for a level outside 0..22.
void checkBlobLevel(int level);

// Where to read blob `info`'s stored bytes before unpackBlob(): `hold`
// itself when they are its contents, else a buffer of the calling thread's
// own (kept, so a loader reads without allocating once it has held the
// largest frame).
std::vector<uint8_t>& storedBuffer(const BlobInfo& info, std::vector<uint8_t>& hold);

// Blob `index`'s contents from its stored bytes (`stored`: info.size of them,
// their CRC already checked). Not compressed: `out` spans `stored` itself.
// Compressed: decompressed into `into` (grown when too small, never shrunk,
// so a caller that keeps it decodes without allocating once it has held the
// largest), `out` spans `into`. Corrupt, naming `name`, the blob and its
// offset, when the frame is damaged or holds other than info.contents_size
// bytes. Thread-safe (each thread keeps its own decompression context).
core::Status unpackBlob(const BlobInfo& info, uint32_t index, const uint8_t* stored, std::vector<uint8_t>& into,
                        Span& out, const std::string& name, std::string& err);

}  // namespace blvd::package
