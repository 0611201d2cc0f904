// --display in a build without X11 (no libx11-dev at configure time).
#include "display.h"

namespace vcan_drive {

std::unique_ptr<Display> openDisplay(uint32_t, uint32_t, std::string& err) {
  err = "--display is not available in this build: it was configured without X11 (install libx11-dev and "
        "reconfigure); write PNG frames with --frames DIR instead";
  return nullptr;
}

}  // namespace vcan_drive
