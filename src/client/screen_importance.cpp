// Screen-area ranking of a client's front (cheng-ooi 2008 §4.2) from the renderer's face-id buffer.
#include "client/screen_importance.h"

#include <algorithm>

#include "spm/vertex_id.h"

namespace pms::client {

const std::vector<VertexArea>& ScreenImportance::rank(const SelectiveMesh& mesh, const ViewParams& view,
                                                      const CanSplit& can_split) {
  mesh.extract(arrays_);
  renderer_.render(RenderMesh{arrays_.positions, arrays_.indices, {}}, view, image_, options_);
  const size_t faces = arrays_.indices.size() / 3;
  face_pixels_.assign(faces, 0);
  covered_ = 0;
  for (uint32_t face : image_.face_id) {
    if (face == kNone) continue;
    ++face_pixels_[face];
    ++covered_;
  }
  vertex_pixels_.assign(arrays_.slots.size(), 0);
  for (size_t f = 0; f < faces; ++f)
    if (face_pixels_[f])
      for (size_t k = 0; k < 3; ++k) vertex_pixels_[arrays_.indices[3 * f + k]] += face_pixels_[f];
  ranked_.clear();
  const VertexHierarchy& hierarchy = mesh.hierarchy();
  for (size_t v = 0; v < arrays_.slots.size(); ++v) {
    const uint32_t slot = arrays_.slots[v];
    if (vertex_pixels_[v] == 0 || !hierarchy.is_leaf(slot) || (can_split && !can_split(slot))) continue;
    ranked_.push_back({slot, vertex_pixels_[v]});
  }
  std::sort(ranked_.begin(), ranked_.end(), [](const VertexArea& a, const VertexArea& b) {
    return a.pixels > b.pixels || (a.pixels == b.pixels && a.slot < b.slot);
  });
  return ranked_;
}

}  // namespace pms::client
