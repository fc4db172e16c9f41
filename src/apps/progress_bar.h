// A one-line progress bar on stderr (phase, percent, ETA), drawn only when stderr is a terminal.
#pragma once
#include <chrono>
#include <string>

#include "common/progress.h"

namespace pms::app {

class ProgressBar {
 public:
  explicit ProgressBar(bool enabled);
  ~ProgressBar();
  ProgressFn callback();
  void finish();  // clears the line

 private:
  void draw(std::string_view phase, double fraction);
  bool enabled_;
  std::string phase_;
  std::chrono::steady_clock::time_point phase_start_, last_draw_;
  bool drawn_ = false;
};

}  // namespace pms::app
