// Headless frames for vcan_drive (C API build only): each rendered frame goes to
// the PNG sequence (--frames), the window (--display) and the frame-time stats;
// renderRecorded() does the same for a poses file recorded elsewhere.
#pragma once

#include <csignal>
#include <memory>
#include <string>
#include <vector>

#include "display.h"
#include "common/logs.h"
#include "tracking.h"

namespace vcan_drive {

class Frames {
 public:
  // `tracking` must render (canRender()). dir: PNG folder, created; "" for none.
  // display: open a window. False with `err` set on failure.
  bool open(Tracking& tracking, const std::string& dir, bool display, std::string& err);

  // Renders at the tracked pose, or at `pose` when given. False on a render or
  // write failure (reported on stderr).
  bool frame(const blvd_pose* pose);
  // The window was closed: the run should stop.
  bool closed() const { return closed_; }
  const samples::RenderStats& stats() const { return stats_; }

 private:
  Tracking* tracking_ = nullptr;
  std::string dir_;
  std::unique_ptr<Display> display_;
  std::vector<unsigned char> rgba_;
  samples::RenderStats stats_;
  bool closed_ = false;
};

// --render-poses: renders every render_every-th valid pose of a poses JSONL
// (as vcan_drive writes it) and writes the stats JSON. Returns the exit status.
int renderRecorded(const std::string& poses_path, unsigned render_every, const std::string& stats_path,
                   Frames& frames, const volatile std::sig_atomic_t& stop);

}  // namespace vcan_drive
