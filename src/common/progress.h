// Long work reports progress through this callback so lower layers never print.
#pragma once
#include <functional>
#include <string_view>

namespace pms {

// phase: short name ("load", "simplify", ...); fraction in [0, 1] within that phase.
using ProgressFn = std::function<void(std::string_view phase, double fraction)>;

inline void report(const ProgressFn& progress, std::string_view phase, double fraction) {
  if (progress) progress(phase, fraction);
}

}  // namespace pms
