// SHA-256 digests (OpenSSL's libcrypto) of a bake's input and options, so
// that shards of one bake can prove they belong together (bake/shard.h).
#pragma once
#include <string>

namespace blvd::bake {

// Lower-case hex SHA-256 of `bytes`.
std::string sha256Hex(const std::string& bytes);

// Lower-case hex SHA-256 of the file's contents, read in pieces. Throws
// core::Error(Io) naming the path when it cannot be read.
std::string sha256FileHex(const std::string& path);

}  // namespace blvd::bake
