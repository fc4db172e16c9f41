// cheng-ooi 2008 §4.2: a front vertex's importance is the screen area of its faces; what every source
// shares once it has counted pixels per face.
#include "client/importance.h"

#include <algorithm>

namespace pms::client {

void rank_by_area(std::span<const uint64_t> face_pixels, std::span<const uint32_t> corners,
                  std::span<const uint32_t> slot_of, const SelectiveMesh& mesh, const CanSplit& can_split,
                  std::vector<uint64_t>& vertex_pixels, std::vector<VertexArea>& ranked) {
  const VertexHierarchy& hierarchy = mesh.hierarchy();
  const size_t vertices = slot_of.empty() ? hierarchy.size() : slot_of.size();
  vertex_pixels.assign(vertices, 0);
  const size_t faces = std::min(face_pixels.size(), corners.size() / 3);
  for (size_t f = 0; f < faces; ++f) {
    if (face_pixels[f] == 0 || corners[3 * f] == kNone) continue;
    for (size_t k = 0; k < 3; ++k) {
      const uint32_t v = corners[3 * f + k];
      if (v < vertices) vertex_pixels[v] += face_pixels[f];
    }
  }
  ranked.clear();
  for (size_t v = 0; v < vertices; ++v) {
    const uint32_t slot = slot_of.empty() ? uint32_t(v) : slot_of[v];
    if (vertex_pixels[v] == 0 || !hierarchy.is_leaf(slot) || (can_split && !can_split(slot))) continue;
    ranked.push_back({slot, vertex_pixels[v]});
  }
  std::sort(ranked.begin(), ranked.end(), [](const VertexArea& a, const VertexArea& b) {
    return a.pixels > b.pixels || (a.pixels == b.pixels && a.slot < b.slot);
  });
}

}  // namespace pms::client
