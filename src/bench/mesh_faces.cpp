#include "bench/mesh_faces.h"

#include <algorithm>

#include "spm/vertex_hierarchy.h"

namespace pms::bench {

std::vector<IdFace> faces_by_id(const SelectiveMesh& mesh) {
  const VertexHierarchy& h = mesh.hierarchy();
  std::vector<IdFace> faces;
  faces.reserve(mesh.face_count());
  for (uint32_t f = 0; f < mesh.face_capacity(); ++f) {
    if (!mesh.face_alive(f)) continue;
    std::array<std::array<uint64_t, 2>, 3> ids;
    for (int k = 0; k < 3; ++k) ids[size_t(k)] = {h.id(mesh.face(f)[k]).tree, h.id(mesh.face(f)[k]).node};
    std::rotate(ids.begin(), std::min_element(ids.begin(), ids.end()), ids.end());
    faces.push_back({ids[0][0], ids[0][1], ids[1][0], ids[1][1], ids[2][0], ids[2][1]});
  }
  std::sort(faces.begin(), faces.end());
  return faces;
}

double shared_percent(const std::vector<IdFace>& faces, const std::vector<IdFace>& reference) {
  size_t common = 0;
  for (size_t i = 0, j = 0; i < faces.size() && j < reference.size();) {
    if (faces[i] < reference[j]) ++i;
    else if (reference[j] < faces[i]) ++j;
    else ++common, ++i, ++j;
  }
  return reference.empty() ? 100 : 100.0 * double(common) / double(reference.size());
}

}  // namespace pms::bench
