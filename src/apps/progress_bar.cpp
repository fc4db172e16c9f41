#include "apps/progress_bar.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace pms::app {

ProgressBar::ProgressBar(bool enabled) : enabled_(enabled && isatty(STDERR_FILENO)) {}

ProgressBar::~ProgressBar() { finish(); }

ProgressFn ProgressBar::callback() {
  if (!enabled_) return {};
  return [this](std::string_view phase, double fraction) { draw(phase, fraction); };
}

void ProgressBar::draw(std::string_view phase, double fraction) {
  const auto now = std::chrono::steady_clock::now();
  if (phase != phase_) {
    phase_ = std::string(phase);
    phase_start_ = now;
  } else if (now - last_draw_ < std::chrono::milliseconds(100) && fraction < 1) {
    return;  // redrawing more often only costs time
  }
  last_draw_ = now;
  fraction = std::clamp(fraction, 0.0, 1.0);
  constexpr int kWidth = 30;
  const int filled = int(fraction * kWidth);
  std::string bar(filled, '#');
  bar.resize(kWidth, '.');
  const double elapsed = std::chrono::duration<double>(now - phase_start_).count();
  char eta[32] = "";
  if (fraction > 0.02 && fraction < 1)
    std::snprintf(eta, sizeof eta, " ETA %.0fs", elapsed * (1 - fraction) / fraction);
  std::fprintf(stderr, "\r%-10s [%s] %3d%%%-12s", phase_.c_str(), bar.c_str(), int(fraction * 100), eta);
  std::fflush(stderr);
  drawn_ = true;
}

void ProgressBar::finish() {
  if (!drawn_) return;
  std::fprintf(stderr, "\r%60s\r", "");
  std::fflush(stderr);
  drawn_ = false;
}

}  // namespace pms::app
