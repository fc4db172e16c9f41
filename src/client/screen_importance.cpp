// Screen-area ranking of a client's front (cheng-ooi 2008 §4.2) from the renderer's face-id buffer.
#include "client/screen_importance.h"

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
  rank_by_area(face_pixels_, arrays_.indices, arrays_.slots, mesh, can_split, vertex_pixels_, ranked_);
  return ranked_;
}

}  // namespace pms::client
