// --display: shows the rendered frames in a window. Built with Xlib when the
// build finds X11 (display_x11.cpp); otherwise open() says the build has no
// window system support (display_none.cpp). Wayland-only sessions are served by
// XWayland; there is no native Wayland path.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

namespace vcan_drive {

class Display {
 public:
  virtual ~Display() = default;
  // Shows one RGBA8 frame (top row first). False once the window was closed.
  virtual bool show(const unsigned char* rgba) = 0;
};

// Null with `err` set when no window can be opened (no $DISPLAY, no X11 in this build).
std::unique_ptr<Display> openDisplay(uint32_t width, uint32_t height, std::string& err);

}  // namespace vcan_drive
