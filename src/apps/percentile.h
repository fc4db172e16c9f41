// Nearest-rank percentile of a sample (latencies, frame times) for the tables the CLI prints.
#pragma once
#include <algorithm>
#include <vector>

namespace pms::app {

// p in [0, 1]; 0 for an empty sample.
inline double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  return values[std::min(values.size() - 1, size_t(p * double(values.size() - 1) + 0.5))];
}

}  // namespace pms::app
