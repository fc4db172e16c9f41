#include <algorithm>

#include "io/mesh.h"

namespace pms {

std::vector<PositionedTriangle> positioned_triangles(std::span<const float> positions,
                                                     std::span<const uint32_t> indices) {
  std::vector<PositionedTriangle> out;
  out.reserve(indices.size() / 3);
  for (size_t t = 0; t + 2 < indices.size(); t += 3) {
    const uint32_t a = indices[t], b = indices[t + 1], c = indices[t + 2];
    if (a == b || b == c || a == c) continue;
    std::array<std::array<float, 3>, 3> corners;
    for (int k = 0; k < 3; ++k)
      for (int x = 0; x < 3; ++x) corners[size_t(k)][size_t(x)] = positions[3 * size_t(indices[t + size_t(k)]) + size_t(x)];
    std::rotate(corners.begin(), std::min_element(corners.begin(), corners.end()), corners.end());
    PositionedTriangle triangle;
    for (size_t k = 0; k < 3; ++k) std::copy(corners[k].begin(), corners[k].end(), triangle.begin() + 3 * long(k));
    out.push_back(triangle);
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace pms
