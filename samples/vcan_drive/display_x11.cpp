// --display through Xlib: an XImage refreshed with each frame read back from
// blvd's off-screen framebuffer. Rendering stays headless (EGL surfaceless or
// OSMesa), so the window needs no GL visual and works over plain X forwarding.
#include <X11/Xlib.h>
#include <X11/Xutil.h>

#include <cstdlib>
#include <cstring>
#include <vector>

#include "display.h"

namespace vcan_drive {
namespace {

class X11Display final : public Display {
 public:
  X11Display(::Display* dpy, uint32_t w, uint32_t h) : dpy_(dpy), w_(w), h_(h), pixels_(size_t(w) * h * 4) {
    const int screen = DefaultScreen(dpy_);
    win_ = XCreateSimpleWindow(dpy_, RootWindow(dpy_, screen), 0, 0, w, h, 0, BlackPixel(dpy_, screen),
                               BlackPixel(dpy_, screen));
    XStoreName(dpy_, win_, "vcan_drive");
    wm_delete_ = XInternAtom(dpy_, "WM_DELETE_WINDOW", False);
    XSetWMProtocols(dpy_, win_, &wm_delete_, 1);
    XSelectInput(dpy_, win_, ExposureMask | KeyPressMask | StructureNotifyMask);
    XMapWindow(dpy_, win_);
    gc_ = XCreateGC(dpy_, win_, 0, nullptr);
    image_ = XCreateImage(dpy_, DefaultVisual(dpy_, screen), static_cast<unsigned>(DefaultDepth(dpy_, screen)),
                          ZPixmap, 0, reinterpret_cast<char*>(pixels_.data()), w, h, 32, 0);
  }
  ~X11Display() override {
    if (image_) {
      image_->data = nullptr;  // pixels_ owns the memory
      XDestroyImage(image_);
    }
    XFreeGC(dpy_, gc_);
    XDestroyWindow(dpy_, win_);
    XCloseDisplay(dpy_);
  }

  bool show(const unsigned char* rgba) override {
    while (XPending(dpy_)) {
      XEvent ev;
      XNextEvent(dpy_, &ev);
      if (ev.type == ClientMessage && static_cast<Atom>(ev.xclient.data.l[0]) == wm_delete_) return false;
      if (ev.type == KeyPress) return false;
    }
    if (!image_) return false;
    // RGBA -> the 24/32-bit TrueColor layout of practically every X server (0x00RRGGBB).
    for (size_t i = 0, n = size_t(w_) * h_; i < n; ++i) {
      pixels_[4 * i + 0] = rgba[4 * i + 2];
      pixels_[4 * i + 1] = rgba[4 * i + 1];
      pixels_[4 * i + 2] = rgba[4 * i + 0];
      pixels_[4 * i + 3] = 0;
    }
    XPutImage(dpy_, win_, gc_, image_, 0, 0, 0, 0, w_, h_);
    XFlush(dpy_);
    return true;
  }

 private:
  ::Display* dpy_;
  uint32_t w_, h_;
  std::vector<unsigned char> pixels_;
  Window win_{};
  GC gc_{};
  XImage* image_ = nullptr;
  Atom wm_delete_{};
};

}  // namespace

std::unique_ptr<Display> openDisplay(uint32_t width, uint32_t height, std::string& err) {
  const char* name = std::getenv("DISPLAY");
  if (!name || !*name) {
    err = "--display: no X server ($DISPLAY is not set; under Wayland, XWayland provides one)";
    return nullptr;
  }
  ::Display* dpy = XOpenDisplay(name);
  if (!dpy) {
    err = std::string("--display: cannot open X display ") + name;
    return nullptr;
  }
  if (DefaultDepth(dpy, DefaultScreen(dpy)) < 24) {
    XCloseDisplay(dpy);
    err = "--display: the X screen is not 24/32-bit TrueColor";
    return nullptr;
  }
  return std::make_unique<X11Display>(dpy, width, height);
}

}  // namespace vcan_drive
