// Axis-aligned bounds of a position array; the diagonal is the model's scale everywhere.
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

namespace pms {

struct Bounds {
  float lo[3] = {INFINITY, INFINITY, INFINITY};
  float hi[3] = {-INFINITY, -INFINITY, -INFINITY};

  float diagonal() const {
    const float d = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                              (hi[2] - lo[2]) * (hi[2] - lo[2]));
    return d > 0 ? d : 1.0f;  // a single point still needs a non-zero unit
  }
};

inline Bounds bounds_of(const std::vector<float>& positions) {
  Bounds b;
  for (size_t i = 0; i < positions.size(); ++i) {
    b.lo[i % 3] = std::min(b.lo[i % 3], positions[i]);
    b.hi[i % 3] = std::max(b.hi[i % 3], positions[i]);
  }
  return b;
}

}  // namespace pms
