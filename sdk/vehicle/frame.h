// One CAN frame as the CAN adapter passes it around: classic CAN, CAN FD, RTR
// and error frames, with a timestamp and the interface it came from.
//
// This is the adapter's own type, not the kernel's struct can_frame, so that a
// candump log, a SocketCAN socket and a host's own driver all produce the same
// thing, and the code compiles where <linux/can.h> does not exist.
#pragma once

#include <cstdint>
#include <string>

namespace blvd::vehicle {

inline constexpr uint32_t kSffMask = 0x7FFu;       // 11-bit standard identifier
inline constexpr uint32_t kEffMask = 0x1FFFFFFFu;  // 29-bit extended identifier
inline constexpr uint8_t kMaxClassicLen = 8;
inline constexpr uint8_t kMaxFdLen = 64;

// CAN FD flags nibble, as in <linux/can.h> (CANFD_BRS, CANFD_ESI, CANFD_FDF).
inline constexpr uint8_t kFdBrs = 0x1;  // bit rate switch
inline constexpr uint8_t kFdEsi = 0x2;  // error state indicator of the sender
inline constexpr uint8_t kFdFdf = 0x4;  // "this is an FD frame" (newer kernels set it)

struct Frame {
  double t = 0;        // seconds; the clock is the source's (Unix time for candump/SocketCAN, boot time for comma2k19)
  uint32_t id = 0;     // arbitration id without flags; for error frames the error class bits (CAN_ERR_*)
  bool extended = false;  // 29-bit id
  bool rtr = false;       // remote transmission request (classic CAN only)
  bool error = false;     // error frame (CAN_ERR_FLAG); id holds the class, data the details
  bool fd = false;        // CAN FD frame (candump "##")
  uint8_t fd_flags = 0;   // CAN FD flags nibble as logged (kFdBrs | kFdEsi | kFdFdf)
  uint8_t dlc = 0;        // payload length in bytes: 0..8, or an FD length up to 64. For RTR the requested length.
  uint8_t len8_dlc = 0;   // classic CAN with 8 bytes: the raw DLC 9..15 when the sender used one, else 0
  uint8_t data[kMaxFdLen] = {};
  std::string iface;      // "can0"; empty when unknown
};

// True for the payload lengths CAN FD can carry (0..8, 12, 16, 20, 24, 32, 48, 64).
inline bool isFdLength(unsigned n) {
  return n <= 8 || n == 12 || n == 16 || n == 20 || n == 24 || n == 32 || n == 48 || n == 64;
}

}  // namespace blvd::vehicle
