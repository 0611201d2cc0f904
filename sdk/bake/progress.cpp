#include "bake/progress.h"

#include <unistd.h>

#include <cstdio>

namespace blvd::bake {

Progress::Progress(bool quiet)
    : quiet_(quiet), tty_(!quiet && isatty(STDERR_FILENO)), start_(std::chrono::steady_clock::now()) {}

Progress::~Progress() { finish(); }

void Progress::stage(const std::string& name) {
  finish();
  stage_ = name;
  last_pct_ = -1;
  stage_start_ = std::chrono::steady_clock::now();
  if (!tty_) std::fprintf(stderr, "bake: %s ...\n", name.c_str());
  else update(0, 1);
}

void Progress::update(double done, double total) {
  if (!tty_ || stage_.empty()) return;
  const int pct = total > 0 ? static_cast<int>(100.0 * done / total) : 0;
  if (pct == last_pct_) return;
  last_pct_ = pct;
  const int width = 30, filled = pct * width / 100;
  std::fprintf(stderr, "\r  %-28s [%.*s%*s] %3d%%", stage_.c_str(), filled, "##############################",
               width - filled, "", pct);
  std::fflush(stderr);
}

void Progress::finish() {
  if (stage_.empty()) return;
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - stage_start_).count();
  if (tty_) {
    last_pct_ = -1;
    update(1, 1);
    std::fprintf(stderr, " %6.2f s\n", s);
  } else if (!quiet_) {
    std::fprintf(stderr, "bake: %s done in %.2f s\n", stage_.c_str(), s);
  }
  stage_.clear();
}

}  // namespace blvd::bake
