// Progress display for long bakes: a redrawn bar on a terminal, plain log
// lines otherwise (or with --quiet, only stage starts and the summary).
#pragma once
#include <chrono>
#include <string>

namespace blvd::bake {

class Progress {
 public:
  explicit Progress(bool quiet);
  ~Progress();
  void stage(const std::string& name);          // starts a stage (finishes the previous one)
  void update(double done, double total);       // within the current stage
  void finish();

 private:
  bool quiet_, tty_;
  std::string stage_;
  int last_pct_ = -1;
  std::chrono::steady_clock::time_point stage_start_, start_;
};

}  // namespace blvd::bake
