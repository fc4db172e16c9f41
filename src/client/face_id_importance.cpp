#include "client/face_id_importance.h"

#include "common/error.h"

namespace pms::client {

// The largest frame taken: 4K by 4K pixels, so a page cannot have the core hold more than 64 MiB of ids.
constexpr uint64_t kMaxPixels = uint64_t(4096) * 4096;

void FaceIdImportance::set_face_ids(std::span<const uint8_t> rgba, uint32_t width, uint32_t height) {
  const uint64_t pixels = uint64_t(width) * height;
  if (pixels * 4 != rgba.size()) fail("face ids", "the frame is not width x height RGBA pixels");
  if (pixels > kMaxPixels) fail("face ids", "a frame of more than 4096 x 4096 pixels");
  ids_.clear();
  for (size_t p = 0; p < rgba.size(); p += 4) {
    const uint32_t id = uint32_t(rgba[p]) | uint32_t(rgba[p + 1]) << 8 | uint32_t(rgba[p + 2]) << 16;
    if (id != 0) ids_.push_back(id);
  }
  ++frames_;
}

// Counted against the mesh as it is now: an id past its faces (a frame drawn before collapses) counts for
// nothing, so the counts never take more than a slot per face.
const std::vector<VertexArea>& FaceIdImportance::rank(const SelectiveMesh& mesh, const ViewParams& view,
                                                      const CanSplit& can_split) {
  (void)view;  // the frame was drawn from the page's camera
  const uint32_t faces = mesh.face_capacity();
  face_pixels_.assign(faces, 0);
  for (const uint32_t id : ids_)
    if (id <= faces) ++face_pixels_[id - 1];
  std::span<const uint32_t> corners;
  if (faces > 0) corners = {mesh.face(0), size_t(faces) * 3};
  rank_by_area(face_pixels_, corners, {}, mesh, can_split, vertex_pixels_, ranked_);
  return ranked_;
}

}  // namespace pms::client
