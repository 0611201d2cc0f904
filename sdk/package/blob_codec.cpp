#include "package/blob_codec.h"

#include "package/blob_dictionary.h"

#include <zstd.h>

#include <memory>
#include <new>


namespace blvd::package {

namespace {

struct DctxFree {
  void operator()(ZSTD_DCtx* c) const { ZSTD_freeDCtx(c); }
};

// One context per thread, made at its first compressed blob and kept: a
// loader thread decompresses every blob after that without allocating. An
// allocation that failed is tried again at the next blob.
ZSTD_DCtx* threadContext() {
  thread_local std::unique_ptr<ZSTD_DCtx, DctxFree> ctx;
  if (!ctx) ctx.reset(ZSTD_createDCtx());
  return ctx.get();
}

struct DdictFree {
  void operator()(ZSTD_DDict* d) const { ZSTD_freeDDict(d); }
};

// The built-in dictionary, digested once for every thread (a DDict is
// read-only once made); null when its allocation failed.
const ZSTD_DDict* dictionary() {
  static const std::unique_ptr<ZSTD_DDict, DdictFree> d = [] {
    const BlobDictionary raw = glbDictionary();
    // Bytes without the dictionary magic are raw content (ZSTD_dct_auto).
    return std::unique_ptr<ZSTD_DDict, DdictFree>(ZSTD_createDDict(raw.data, raw.size));
  }();
  return d.get();
}

struct CctxFree {
  void operator()(ZSTD_CCtx* c) const { ZSTD_freeCCtx(c); }
};

// `contents` as one frame at `level`, with the built-in dictionary or not.
std::vector<uint8_t> frame(ZSTD_CCtx* ctx, const std::vector<uint8_t>& contents, int level, bool with_dictionary) {
  const BlobDictionary d = glbDictionary();
  std::vector<uint8_t> z(ZSTD_compressBound(contents.size()));
  const size_t n = with_dictionary ? ZSTD_compress_usingDict(ctx, z.data(), z.size(), contents.data(),
                                                             contents.size(), d.data, d.size, level)
                                   : ZSTD_compressCCtx(ctx, z.data(), z.size(), contents.data(), contents.size(), level);
  if (ZSTD_isError(n)) throw core::Error(core::Status::Internal, std::string("zstd: ") + ZSTD_getErrorName(n));
  z.resize(n);
  z.shrink_to_fit();
  return z;
}

core::Status bad(const BlobInfo& info, uint32_t index, const std::string& name, const std::string& why,
                 std::string& err) {
  err = name + ": blob " + std::to_string(index) + " at offset " + std::to_string(info.offset) + ": " + why;
  return core::Status::Corrupt;
}

}  // namespace

void checkBlobLevel(int level) {
  if (level < 0 || level > ZSTD_maxCLevel())
    throw core::Error(core::Status::InvalidArg, "blob compression level " + std::to_string(level) +
                                                    " is outside 0.." + std::to_string(ZSTD_maxCLevel()));
}

StoredBlob packBlob(std::vector<uint8_t> contents, int level) {
  checkBlobLevel(level);
  if (contents.size() > kMaxBlobContentsBytes)
    throw core::Error(core::Status::InvalidArg, "blob of " + std::to_string(contents.size()) +
                                                    " bytes is over the package's limit of " +
                                                    std::to_string(kMaxBlobContentsBytes));
  StoredBlob out;
  out.contents_size = contents.size();
  if (level > 0 && !contents.empty()) {
    std::unique_ptr<ZSTD_CCtx, CctxFree> ctx(ZSTD_createCCtx());
    if (!ctx) throw std::bad_alloc();
    std::vector<uint8_t> plain = frame(ctx.get(), contents, level, false), dict = frame(ctx.get(), contents, level, true);
    const bool use_dict = dict.size() < plain.size();
    std::vector<uint8_t>& z = use_dict ? dict : plain;
    if (z.size() < contents.size()) {
      out.bytes = std::move(z);
      out.flags = use_dict ? kBlobZstd | kBlobZstdDict : kBlobZstd;
      return out;
    }
  }
  out.bytes = std::move(contents);
  return out;
}

std::vector<uint8_t>& storedBuffer(const BlobInfo& info, std::vector<uint8_t>& hold) {
  thread_local std::vector<uint8_t> frames;
  return (info.flags & kBlobZstd) ? frames : hold;
}

core::Status unpackBlob(const BlobInfo& info, uint32_t index, const uint8_t* stored, std::vector<uint8_t>& into,
                        Span& out, const std::string& name, std::string& err) {
  out = Span{};
  if ((info.flags & kBlobZstd) == 0) {
    out = Span{stored, static_cast<size_t>(info.size), info.offset};
    return core::Status::Ok;
  }
  ZSTD_DCtx* ctx = threadContext();
  if (!ctx) {
    err = name + ": blob " + std::to_string(index) + ": out of memory for a zstd context";
    return core::Status::NoMem;
  }
  const size_t want = static_cast<size_t>(info.contents_size);
  try {
    if (into.size() < want) into.resize(want);
  } catch (const std::bad_alloc&) {
    err = name + ": blob " + std::to_string(index) + ": out of memory for its " + std::to_string(want) + " bytes";
    return core::Status::NoMem;
  }
  const ZSTD_DDict* dict = (info.flags & kBlobZstdDict) ? dictionary() : nullptr;
  if ((info.flags & kBlobZstdDict) && !dict) {
    err = name + ": blob " + std::to_string(index) + ": out of memory for the zstd dictionary";
    return core::Status::NoMem;
  }
  const size_t n = dict ? ZSTD_decompress_usingDDict(ctx, into.data(), want, stored, static_cast<size_t>(info.size), dict)
                        : ZSTD_decompressDCtx(ctx, into.data(), want, stored, static_cast<size_t>(info.size));
  if (ZSTD_isError(n)) return bad(info, index, name, std::string("zstd frame: ") + ZSTD_getErrorName(n), err);
  if (n != want)
    return bad(info, index, name,
               "zstd frame holds " + std::to_string(n) + " bytes, BIDX says " + std::to_string(want), err);
  out = Span{into.data(), want, info.offset};
  return core::Status::Ok;
}

}  // namespace blvd::package
