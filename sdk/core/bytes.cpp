#include "core/bytes.h"

namespace blvd::core {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "blvd's formats are little-endian; big-endian hosts need byte swaps here");

void ByteReader::fail(const std::string& why, uint64_t at) const {
  throw Error(Status::Corrupt, what_ + " at offset " + std::to_string(base_ + at) + ": " + why);
}

}  // namespace blvd::core
