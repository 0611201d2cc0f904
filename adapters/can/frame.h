// The CAN adapter passes frames around as the SDK's vehicle::Frame (sdk/vehicle
// frame.h): the DBC decoder and the vehicle profiles moved into the SDK so that
// blvd_feed_can_frame() can use them (docs/decisions/0005-can-profiles-in-sdk.md),
// and the candump reader, the SocketCAN source and the profiles must agree on one
// frame type. These names keep the adapter's own spelling, can::Frame.
#pragma once

#include "vehicle/frame.h"

namespace blvd::can {

using vehicle::Frame;
using vehicle::isFdLength;
using vehicle::kEffMask;
using vehicle::kFdBrs;
using vehicle::kFdEsi;
using vehicle::kFdFdf;
using vehicle::kMaxClassicLen;
using vehicle::kMaxFdLen;
using vehicle::kSffMask;

}  // namespace blvd::can
